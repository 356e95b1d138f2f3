#pragma once
// A simulated world: textured planar rectangles. Each plane is given by its centre, two orthonormal
// in-plane axes (u: increasing texture column, v: increasing texture row) and a metric size; its
// texture maps to it at `texel` metres per texel. This is the model of ESIM's planar scenes and of
// ../shared/data/esim_poster6dof_planar/scene.txt, so that scene can be rebuilt exactly.
#include <filesystem>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "core/se3.hpp"

namespace eds::sim {

// How a texture image becomes scene intensity: I = offset + gain * texture / 255, in (0, 1].
struct TextureSpec {
  std::string source;         // image file, or "procedural:<name>[:seed]" (see textures.hpp)
  int width = 0, height = 0;  // resize to this many texels (INTER_AREA); 0 = keep the image size
  double blur_sigma = 0.0;    // Gaussian blur in texels after resizing
  double offset = 0.1, gain = 0.9;
};

struct Plane {
  std::string name;
  Vec3 center = Vec3::Zero();         // world frame: the texture's centre
  Vec3 u = Vec3::UnitX();             // unit, direction of increasing texture column
  Vec3 v = Vec3::UnitY();             // unit, direction of increasing texture row, orthogonal to u
  double size_u = 1.0, size_v = 1.0;  // metric extent along u and v (the rectangle)
  double texel = 0.001;               // metres per texel
  int texture = 0;                    // index into Scene::textures
  // Normal u x v; rays hit both sides.
  Vec3 normal() const { return u.cross(v); }
};

struct Scene {
  std::vector<TextureSpec> texture_specs;
  std::vector<cv::Mat> textures;  // CV_32F intensity (after offset/gain), filled by loadTextures()
  std::vector<Plane> planes;
  bool mirror_outside = false;  // sample the texture beyond its edges mirrored (ESIM's scene.txt
                                // plane is unbounded); otherwise the rectangle ends at its size

  // Loads and prepares every texture (resize, blur, intensity mapping). Throws InputError naming the
  // texture file if unreadable. `base` resolves relative paths.
  void loadTextures(const std::filesystem::path& base = {});
};

// YAML scene description (see docs in scene_io.cpp). Throws InputError naming the file and line.
Scene readSceneYaml(const std::filesystem::path& file);
void writeSceneYaml(const std::filesystem::path& file, const Scene& scene);
// The settings on scene.txt's `esim` line (how ESIM turned the renders into events).
struct EsimParams {
  double C_pos = 0.2, C_neg = 0.2;
  double refractory_s = 0.0;
  double log_eps = 1e-3;  // L = log(I + log_eps)
  bool use_log = true;
  double render_hz = 1000.0;
};

// The ECD/ESIM scene.txt of the shared sequence (P0, n, u, v, texture, intensity lines). The texture
// file is looked up in `texture_dir` (the scene file's folder if empty). Fills `esim` if given.
Scene readEsimSceneTxt(const std::filesystem::path& file, const std::filesystem::path& texture_dir,
                       EsimParams* esim = nullptr);

}  // namespace eds::sim
