// Scene files.
//
// YAML scene (eds simulate --scene FILE), every field written by writeSceneYaml:
//
//   mirror_outside: false        # optional (default false): planes unbounded, texture mirrored beyond
//   textures:                    # at least one
//     - source: office.jpg       # image file (relative to this file's folder) or procedural:<name>[:seed]
//       width: 1600              # optional: texels after resizing (0 or absent: keep the image size;
//       height: 1200             #   procedural default 1024)
//       blur_sigma: 1.0          # optional (0): Gaussian blur, texels
//       offset: 0.1              # optional (0.1): intensity = offset + gain * texture / 255
//       gain: 0.9                # optional (0.9)
//   planes:                      # at least one
//     - name: poster             # optional (plane<i>)
//       center: [x, y, z]        # world frame, metres: the texture's centre
//       u: [x, y, z]             # unit: texture columns increase along u
//       v: [x, y, z]             # unit, orthogonal to u: texture rows increase along v
//       size: [su, sv]           # metric extent along u and v
//       texel: 0.0025            # metres per texel
//       texture: 0               # index into textures
//
// Unknown keys are errors (a typo must not silently fall back to a default). Axes within 1e-3 of
// orthonormal are accepted and re-orthonormalized.
#include <yaml-cpp/yaml.h>

#include <charconv>
#include <cmath>
#include <fstream>
#include <initializer_list>
#include <optional>
#include <sstream>
#include <vector>

#include "core/error.hpp"
#include "sim/scene.hpp"
#include "sim/textures.hpp"

namespace eds::sim {

namespace {

constexpr double kAxisTolerance = 1e-3;

// Makes (u, v) exactly orthonormal when they are close; returns false when they are not close.
bool orthonormalize(Vec3& u, Vec3& v) {
  if (!u.allFinite() || !v.allFinite()) return false;
  if (std::abs(u.norm() - 1) > kAxisTolerance || std::abs(v.norm() - 1) > kAxisTolerance ||
      std::abs(u.dot(v)) > kAxisTolerance)
    return false;
  // Already exact axes stay bit-identical, so files round-trip.
  if (std::abs(u.squaredNorm() - 1) > 1e-12 || std::abs(v.squaredNorm() - 1) > 1e-12 ||
      std::abs(u.dot(v)) > 1e-12) {
    u.normalize();
    v = (v - v.dot(u) * u).normalized();
  }
  return true;
}

bool isProcedural(const std::string& source) { return source.rfind("procedural:", 0) == 0; }

// ---------------------------------------------------------------- ESIM scene.txt

std::optional<double> parseDouble(const std::string& s) {
  double v = 0;
  const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc() || ptr != s.data() + s.size() || !std::isfinite(v)) return std::nullopt;
  return v;
}

// One line of an ESIM scene.txt, split into tokens, with its number parsers.
struct SceneLine {
  const std::string& fname;
  std::size_t lineno;
  std::vector<std::string> tok;

  double num(std::size_t i) const {
    if (i >= tok.size()) throw InputError(fname, lineno, "'" + tok[0] + "': missing value");
    const auto d = parseDouble(tok[i]);
    if (!d) throw InputError(fname, lineno, "'" + tok[0] + "': bad number '" + tok[i] + "'");
    return *d;
  }
  Vec3 vec() const {
    if (tok.size() != 4) throw InputError(fname, lineno, "'" + tok[0] + "' needs 3 numbers");
    return Vec3(num(1), num(2), num(3));
  }
};

// texture NAME W H TEXEL [blur_sigma_texels S]
TextureSpec parseTexture(const SceneLine& l, const std::filesystem::path& dir, double& texel) {
  const auto& tok = l.tok;
  if (tok.size() < 5 || tok.size() % 2 == 0)
    throw InputError(l.fname, l.lineno, "expected 'texture NAME W H TEXEL [blur_sigma_texels S]'");
  TextureSpec spec;
  spec.source = (dir / tok[1]).string();
  const double w = l.num(2), h = l.num(3);
  texel = l.num(4);
  if (w < 1 || h < 1 || w != std::floor(w) || h != std::floor(h) || texel <= 0)
    throw InputError(l.fname, l.lineno, "texture size must be positive integers and texel positive");
  spec.width = static_cast<int>(w), spec.height = static_cast<int>(h);
  for (std::size_t i = 5; i + 1 < tok.size(); i += 2) {
    if (tok[i] != "blur_sigma_texels") throw InputError(l.fname, l.lineno, "unknown texture option '" + tok[i] + "'");
    spec.blur_sigma = l.num(i + 1);
    if (spec.blur_sigma < 0) throw InputError(l.fname, l.lineno, "blur sigma must be >= 0");
  }
  return spec;
}

// esim KEY VALUE ...: the settings that change what is rendered; the others are ignored.
void parseEsimSettings(const SceneLine& l, EsimParams& params) {
  const auto& tok = l.tok;
  if (tok.size() % 2 == 0) throw InputError(l.fname, l.lineno, "expected 'esim KEY VALUE ...'");
  for (std::size_t i = 1; i + 1 < tok.size(); i += 2) {
    const double val = l.num(i + 1);
    if (tok[i] == "Cpos")
      params.C_pos = val;
    else if (tok[i] == "Cneg")
      params.C_neg = val;
    else if (tok[i] == "refractory")
      params.refractory_s = val;
    else if (tok[i] == "log_eps")
      params.log_eps = val;
    else if (tok[i] == "use_log")
      params.use_log = val != 0;
    else if (tok[i] == "render_hz")
      params.render_hz = val;
  }
}

}  // namespace

Scene readEsimSceneTxt(const std::filesystem::path& file, const std::filesystem::path& texture_dir,
                       EsimParams* esim) {
  const std::string fname = file.string();
  std::ifstream in(file);
  if (!in) throw InputError(fname, "cannot open scene file");
  std::optional<Vec3> P0, n, u, v;
  std::size_t n_line = 0, v_line = 0;
  std::optional<TextureSpec> tex;
  double texel = 0;
  TextureSpec intensity;  // offset and gain defaults
  EsimParams params;
  std::string line;
  for (std::size_t lineno = 1; std::getline(in, line); ++lineno) {
    if (const auto hash = line.find('#'); hash != std::string::npos) line.resize(hash);
    std::istringstream ss(line);
    SceneLine l{fname, lineno, {}};
    for (std::string t; ss >> t;) l.tok.push_back(t);
    if (l.tok.empty()) continue;
    const std::string& key = l.tok[0];
    if (key == "P0") {
      P0 = l.vec();
    } else if (key == "n") {
      n = l.vec(), n_line = lineno;
    } else if (key == "u") {
      u = l.vec();
    } else if (key == "v") {
      v = l.vec(), v_line = lineno;
    } else if (key == "texture") {
      tex = parseTexture(l, texture_dir.empty() ? file.parent_path() : texture_dir, texel);
    } else if (key == "intensity") {
      if (l.tok.size() != 3) throw InputError(fname, lineno, "expected 'intensity OFFSET GAIN'");
      intensity.offset = l.num(1), intensity.gain = l.num(2);
      if (intensity.offset < 0 || intensity.gain <= 0)
        throw InputError(fname, lineno, "intensity offset must be >= 0 and gain > 0");
    } else if (key == "esim") {
      parseEsimSettings(l, params);
    } else {
      throw InputError(fname, lineno, "unknown key '" + key + "'");
    }
  }
  if (!P0 || !u || !v || !tex) throw InputError(fname, "missing one of P0, u, v, texture");
  Vec3 uu = *u, vv = *v;
  if (!orthonormalize(uu, vv)) throw InputError(fname, v_line, "u and v are not orthonormal (to 1e-3)");
  if (n) {
    // scene.txt gives the normal towards the camera, which may be either sign of u x v.
    const Vec3 uxv = uu.cross(vv);
    if (std::min((*n - uxv).norm(), (*n + uxv).norm()) > 1e-2)
      throw InputError(fname, n_line, "n is not the normal of u and v (+-u x v)");
  }
  tex->offset = intensity.offset, tex->gain = intensity.gain;
  Scene scene;
  scene.texture_specs.push_back(*tex);
  Plane plane;
  plane.name = "esim_plane";
  plane.center = *P0, plane.u = uu, plane.v = vv;
  plane.texel = texel;
  plane.size_u = tex->width * texel, plane.size_v = tex->height * texel;
  plane.texture = 0;
  scene.planes.push_back(plane);
  scene.mirror_outside = true;  // "bilinear, mirrored border": ESIM's plane is unbounded
  if (esim) *esim = params;
  return scene;
}

// ---------------------------------------------------------------- YAML

namespace {

class YamlReader {
 public:
  explicit YamlReader(std::string file) : file_(std::move(file)) {}

  [[noreturn]] void fail(const YAML::Node& node, const std::string& msg) const {
    const int line = node.Mark().line;  // 0-based; -1 for nodes without a position
    throw InputError(file_, line >= 0 ? static_cast<std::size_t>(line) + 1 : 0, msg);
  }

  YAML::Node required(const YAML::Node& map, const char* key) const {
    const YAML::Node n = map[key];
    if (!n) fail(map, std::string("missing key '") + key + "'");
    return n;
  }

  void checkMap(const YAML::Node& n, const char* what, std::initializer_list<const char*> keys) const {
    if (!n.IsMap()) fail(n, std::string(what) + ": expected a map");
    for (const auto& kv : n) {
      const std::string k = kv.first.Scalar();
      bool known = false;
      for (const char* key : keys) known = known || k == key;
      if (!known) fail(kv.first, std::string(what) + ": unknown key '" + k + "'");
    }
  }

  double number(const YAML::Node& n, const std::string& what) const {
    double v = 0;
    try {
      if (!n.IsScalar()) fail(n, what + ": expected a number");
      v = n.as<double>();
    } catch (const YAML::Exception&) {
      fail(n, what + ": expected a number, got '" + n.Scalar() + "'");
    }
    if (!std::isfinite(v)) fail(n, what + ": not a finite number");
    return v;
  }

  int integer(const YAML::Node& n, const std::string& what) const {
    try {
      if (n.IsScalar()) return n.as<int>();
    } catch (const YAML::Exception&) {
    }
    fail(n, what + ": expected an integer");
  }

  Eigen::VectorXd vector(const YAML::Node& n, int size, const std::string& what) const {
    if (!n.IsSequence() || static_cast<int>(n.size()) != size)
      fail(n, what + ": expected a list of " + std::to_string(size) + " numbers");
    Eigen::VectorXd v(size);
    for (int i = 0; i < size; ++i) v[i] = number(n[i], what);
    return v;
  }

 private:
  std::string file_;
};

TextureSpec readTextureSpec(const YamlReader& r, const YAML::Node& n, const std::filesystem::path& folder) {
  r.checkMap(n, "texture", {"source", "width", "height", "blur_sigma", "offset", "gain"});
  TextureSpec spec;
  const YAML::Node src = r.required(n, "source");
  spec.source = src.IsScalar() ? src.Scalar() : "";
  if (spec.source.empty()) r.fail(src, "texture source must be a non-empty string");
  try {
    parseProceduralSource(spec.source);
  } catch (const std::invalid_argument& e) {
    r.fail(src, e.what());
  }
  // Relative image paths are relative to the scene file; made absolute so the scene works from any
  // working directory (and a base given to loadTextures() leaves them alone).
  if (!isProcedural(spec.source) && std::filesystem::path(spec.source).is_relative())
    spec.source = (std::filesystem::absolute(folder) / spec.source).lexically_normal().string();
  if (n["width"]) spec.width = r.integer(n["width"], "width");
  if (n["height"]) spec.height = r.integer(n["height"], "height");
  // The upper bound catches typos before they become gigabytes of texture.
  if (spec.width < 0 || spec.height < 0 || spec.width > 16384 || spec.height > 16384)
    r.fail(n, "texture width and height must be in [0, 16384]");
  if (n["blur_sigma"]) spec.blur_sigma = r.number(n["blur_sigma"], "blur_sigma");
  if (spec.blur_sigma < 0) r.fail(n["blur_sigma"], "blur_sigma must be >= 0");
  if (n["offset"]) spec.offset = r.number(n["offset"], "offset");
  if (n["gain"]) spec.gain = r.number(n["gain"], "gain");
  // The renderer takes the log of intensities: they must stay positive (a small offset > 0 or gain).
  if (spec.offset < 0 || spec.gain <= 0) r.fail(n, "texture offset must be >= 0 and gain > 0");
  return spec;
}

Plane readPlane(const YamlReader& r, const YAML::Node& n, std::size_t index, std::size_t n_textures) {
  r.checkMap(n, "plane", {"name", "center", "u", "v", "size", "texel", "texture"});
  Plane p;
  p.name = "plane" + std::to_string(index);
  if (const YAML::Node name = n["name"]) {
    if (!name.IsScalar()) r.fail(name, "plane name must be a string");
    p.name = name.Scalar();
  }
  p.center = r.vector(r.required(n, "center"), 3, "center");
  p.u = r.vector(r.required(n, "u"), 3, "u");
  p.v = r.vector(r.required(n, "v"), 3, "v");
  if (!orthonormalize(p.u, p.v))
    r.fail(n["v"], "plane '" + p.name + "': u and v must be orthonormal (to 1e-3)");
  const YAML::Node size = r.required(n, "size");
  const Eigen::VectorXd s = r.vector(size, 2, "size");
  p.size_u = s[0], p.size_v = s[1];
  if (p.size_u <= 0 || p.size_v <= 0) r.fail(size, "plane '" + p.name + "': size must be positive");
  const YAML::Node texel = r.required(n, "texel");
  p.texel = r.number(texel, "texel");
  if (p.texel <= 0) r.fail(texel, "plane '" + p.name + "': texel must be positive");
  const YAML::Node tex = r.required(n, "texture");
  p.texture = r.integer(tex, "texture");
  if (p.texture < 0 || static_cast<std::size_t>(p.texture) >= n_textures)
    r.fail(tex, "plane '" + p.name + "': texture index " + std::to_string(p.texture) + " out of range (" +
                    std::to_string(n_textures) + " textures)");
  return p;
}

// Shortest decimal that reads back to the same double: files round-trip exactly and stay readable.
std::string formatDouble(double v) {
  char buf[32];
  const auto res = std::to_chars(buf, buf + sizeof(buf), v);
  return std::string(buf, res.ptr);
}

void emitNumbers(YAML::Emitter& e, std::initializer_list<double> values) {
  e << YAML::Flow << YAML::BeginSeq;
  for (double v : values) e << formatDouble(v);
  e << YAML::EndSeq;
}

}  // namespace

Scene readSceneYaml(const std::filesystem::path& file) {
  const std::string fname = file.string();
  YAML::Node loaded;
  try {
    loaded = YAML::LoadFile(fname);
  } catch (const YAML::BadFile&) {
    throw InputError(fname, "cannot open scene file");
  } catch (const YAML::Exception& e) {
    throw InputError(fname, e.mark.line >= 0 ? static_cast<std::size_t>(e.mark.line) + 1 : 0, e.msg);
  }
  const YAML::Node root = loaded;  // const: lookups of absent keys must not insert them
  const YamlReader r(fname);
  if (!root.IsMap()) throw InputError(fname, "expected a map with 'textures' and 'planes'");
  r.checkMap(root, "scene", {"mirror_outside", "textures", "planes"});
  Scene scene;
  try {
    if (root["mirror_outside"]) scene.mirror_outside = root["mirror_outside"].as<bool>();
  } catch (const YAML::Exception&) {
    r.fail(root["mirror_outside"], "mirror_outside: expected true or false");
  }
  const YAML::Node textures = r.required(root, "textures");
  if (!textures.IsSequence() || textures.size() == 0) r.fail(textures, "textures: expected a non-empty list");
  const std::filesystem::path folder = file.parent_path();
  for (const YAML::Node& t : textures) scene.texture_specs.push_back(readTextureSpec(r, t, folder));
  const YAML::Node planes = r.required(root, "planes");
  if (!planes.IsSequence() || planes.size() == 0) r.fail(planes, "planes: expected a non-empty list");
  for (const YAML::Node& p : planes)
    scene.planes.push_back(readPlane(r, p, scene.planes.size(), scene.texture_specs.size()));
  return scene;
}

void writeSceneYaml(const std::filesystem::path& file, const Scene& scene) {
  const std::filesystem::path folder = std::filesystem::absolute(file.parent_path()).lexically_normal();
  YAML::Emitter e;
  e << YAML::Comment("eds simulator scene: textured rectangles (format: src/sim/scene_io.cpp)");
  e << YAML::BeginMap;
  e << YAML::Key << "mirror_outside" << YAML::Value << scene.mirror_outside;
  e << YAML::Key << "textures" << YAML::Value << YAML::BeginSeq;
  for (const TextureSpec& t : scene.texture_specs) {
    std::string source = t.source;
    if (!isProcedural(source)) {
      // Relative to the scene file, so a folder moved with its textures still works.
      const auto abs = std::filesystem::absolute(source).lexically_normal();
      const auto rel = abs.lexically_relative(folder);
      source = rel.empty() ? abs.string() : rel.string();
    }
    e << YAML::BeginMap << YAML::Key << "source" << YAML::Value << source;
    e << YAML::Key << "width" << YAML::Value << t.width << YAML::Key << "height" << YAML::Value << t.height;
    e << YAML::Key << "blur_sigma" << YAML::Value << formatDouble(t.blur_sigma);
    e << YAML::Key << "offset" << YAML::Value << formatDouble(t.offset);
    e << YAML::Key << "gain" << YAML::Value << formatDouble(t.gain) << YAML::EndMap;
  }
  e << YAML::EndSeq;
  e << YAML::Key << "planes" << YAML::Value << YAML::BeginSeq;
  for (const Plane& p : scene.planes) {
    e << YAML::BeginMap << YAML::Key << "name" << YAML::Value << p.name;
    e << YAML::Key << "center" << YAML::Value;
    emitNumbers(e, {p.center.x(), p.center.y(), p.center.z()});
    e << YAML::Key << "u" << YAML::Value;
    emitNumbers(e, {p.u.x(), p.u.y(), p.u.z()});
    e << YAML::Key << "v" << YAML::Value;
    emitNumbers(e, {p.v.x(), p.v.y(), p.v.z()});
    e << YAML::Key << "size" << YAML::Value;
    emitNumbers(e, {p.size_u, p.size_v});
    e << YAML::Key << "texel" << YAML::Value << formatDouble(p.texel);
    e << YAML::Key << "texture" << YAML::Value << p.texture << YAML::EndMap;
  }
  e << YAML::EndSeq << YAML::EndMap;
  std::ofstream out(file);
  out << e.c_str() << "\n";
  if (!out) throw InputError(file.string(), "cannot write scene file");
}

}  // namespace eds::sim
