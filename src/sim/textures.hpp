#pragma once
// Procedural textures so presets need no image files: CV_8U grayscale images with texture at many
// scales (like natural images), deterministic for a seed.
#include <cstdint>
#include <opencv2/core.hpp>
#include <optional>
#include <string>

namespace eds::sim {

// name: "noise" (multi-octave value noise), "checker", "bricks", "blobs", "stripes", "mix".
// Throws std::invalid_argument for an unknown name.
cv::Mat proceduralTexture(const std::string& name, int width, int height, std::uint64_t seed);
const char* proceduralNames();  // "noise, checker, bricks, blobs, stripes, mix"

// A TextureSpec source "procedural:<name>[:seed]" (seed 0 when absent).
struct ProceduralSource {
  std::string name;
  std::uint64_t seed = 0;
};
// nullopt if `source` is not procedural (an image file); throws std::invalid_argument for an unknown
// name or a malformed seed.
std::optional<ProceduralSource> parseProceduralSource(const std::string& source);
// Size of a procedural texture whose TextureSpec gives no width/height.
inline constexpr int kDefaultProceduralSize = 1024;

}  // namespace eds::sim
