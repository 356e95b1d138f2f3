#pragma once
// Built-in scenes, placed relative to the camera path (in front of where the camera looks over the
// window), never at fixed world coordinates, so any trajectory file works.
#include <string>

#include "sim/motion.hpp"
#include "sim/scene.hpp"

namespace eds::sim {

// planar: one textured plane ~1 m in front (like the shared ESIM sequence).
// room:   floor, ceiling, walls and several boxes at 1-7 m, occlusions, several textures.
// desk:   near objects (0.4-1 m) in front of a far wall (3-5 m): strong parallax.
// building: a courtyard, facades and pillars at 4-14 m: a large depth range, median depth several
//         metres (the sensitivity studies).
// Throws std::invalid_argument for an unknown name (listing the known ones).
Scene makePreset(const std::string& name, const Motion& motion, std::uint64_t seed);
const char* presetNames();  // "planar, room, desk, building"

}  // namespace eds::sim
