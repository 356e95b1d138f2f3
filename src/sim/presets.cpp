#include "sim/presets.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace eds::sim {

namespace {

constexpr double kMinClearance = 0.3;  // metres between any plane and any camera position
constexpr double kFocalRef = 200.0;    // px: the focal length texel sizes are chosen for (240x180)

// Where the camera looks over the window: scenes are built in this frame (x right, y down, z along
// the mean optical axis, origin at the mean position), so they suit any trajectory.
struct ViewFrame {
  Vec3 origin, right, down, fwd;
  Vec3 point(double x, double y, double z) const { return origin + x * right + y * down + z * fwd; }
  Vec3 dir(double x, double y, double z) const { return x * right + y * down + z * fwd; }
  Vec3 local(const Vec3& p) const {
    const Vec3 d = p - origin;
    return {d.dot(right), d.dot(down), d.dot(fwd)};
  }
};

ViewFrame viewFrame(const std::vector<Vec3>& positions, const Motion& motion) {
  Vec3 c = Vec3::Zero(), f = Vec3::Zero(), up = Vec3::Zero();
  for (const StampedPose& p : motion.samples()) {
    f += p.T_w_c.so3() * Vec3::UnitZ();
    up -= p.T_w_c.so3() * Vec3::UnitY();
  }
  for (const Vec3& p : positions) c += p;
  c /= static_cast<double>(positions.size());
  // A camera spinning all round has no mean direction: take the middle pose's.
  const SE3 mid = motion.pose(motion.start() + (motion.end() - motion.start()) / 2);
  if (f.norm() < 1e-6 * motion.samples().size()) f = mid.so3() * Vec3::UnitZ();
  f.normalize();
  up -= up.dot(f) * f;
  if (up.norm() < 1e-6) up = -(mid.so3() * Vec3::UnitY()) + (mid.so3() * Vec3::UnitY()).dot(f) * f;
  if (up.norm() < 1e-6) up = f.unitOrthogonal();
  up.normalize();
  ViewFrame v;
  v.origin = c, v.fwd = f, v.down = -up;
  v.right = v.down.cross(f);  // camera convention: x = y cross z
  return v;
}

double rectDistance(const Plane& p, const Vec3& x) {
  const Vec3 d = x - p.center;
  const double a = std::clamp(d.dot(p.u), -0.5 * p.size_u, 0.5 * p.size_u);
  const double b = std::clamp(d.dot(p.v), -0.5 * p.size_v, 0.5 * p.size_v);
  return (d - a * p.u - b * p.v).norm();
}

class Rng {
 public:
  explicit Rng(std::uint64_t seed) : gen_(seed) {}
  // From raw bits: std::uniform_real_distribution is not the same in every standard library.
  double uniform(double a, double b) { return a + (b - a) * static_cast<double>(gen_() >> 11) * 0x1.0p-53; }
  std::uint64_t next() { return gen_(); }

 private:
  std::mt19937_64 gen_;
};

struct Box {
  std::string name;
  double x, z;     // centre of the bottom face in the view frame
  double bottom;   // y of the bottom face (y down)
  double w, h, d;  // along right, up, forward (before yaw)
  double yaw;      // about the vertical, rad
};

class SceneBuilder {
 public:
  SceneBuilder(const ViewFrame& frame, std::vector<Vec3> cameras, std::uint64_t seed)
      : frame_(frame), cams_(std::move(cameras)), rng_(seed) {
    lo_ = hi_ = frame_.local(cams_.front());
    for (const Vec3& p : cams_) {
      const Vec3 l = frame_.local(p);
      lo_ = lo_.cwiseMin(l), hi_ = hi_.cwiseMax(l);
    }
  }
  const Vec3& lo() const { return lo_; }  // extent of the camera positions in the view frame
  const Vec3& hi() const { return hi_; }
  Rng& rng() { return rng_; }

  // A procedural texture covering su x sv metres at `texel` (the renderer mirrors it beyond 2048).
  int texture(const std::string& kind, double su, double sv, double texel, double blur) {
    auto texels = [&](double s) {
      return std::clamp(static_cast<int>(std::ceil(s / texel / 16.0)) * 16, 128, 2048);
    };
    TextureSpec t;
    t.source = "procedural:" + kind + ":" + std::to_string(rng_.next() % 1000000007ULL);
    t.width = texels(su), t.height = texels(sv);
    t.blur_sigma = blur;
    scene_.texture_specs.push_back(t);
    return static_cast<int>(scene_.texture_specs.size()) - 1;
  }

  // Texel size that makes one texel `px` pixels at distance `z` for the reference focal length.
  static double texelFor(double z, double px) { return px * z / kFocalRef; }

  // A rectangle with a texture of `kind` (texel: its size in metres).
  void texturedRect(const std::string& name, const Vec3& centre, const Vec3& u, const Vec3& v, double su,
                    double sv, double texel, const std::string& kind, const Vec3& push) {
    rect(name, centre, u, v, su, sv, texel, texture(kind, su, sv, texel, 0.5), push);
  }

  // A rectangle given in the view frame; pushed along `push` (view frame) until clear of the cameras.
  void rect(const std::string& name, const Vec3& centre, const Vec3& u, const Vec3& v, double su, double sv,
            double texel, int tex, const Vec3& push) {
    Plane p;
    p.name = name;
    p.center = frame_.point(centre.x(), centre.y(), centre.z());
    p.u = frame_.dir(u.x(), u.y(), u.z()).normalized();
    p.v = frame_.dir(v.x(), v.y(), v.z()).normalized();
    p.size_u = su, p.size_v = sv, p.texel = texel, p.texture = tex;
    std::vector<Plane> group{p};
    addClear(group, frame_.dir(push.x(), push.y(), push.z()));
  }

  // A box with a texture of `kind` at about one texel per pixel from its distance.
  void texturedBox(const Box& b, const std::string& kind) {
    const double texel = texelFor(b.z, 1.0);
    box(b, texel, texture(kind, std::max(b.w, b.d), std::max(b.h, b.d), texel, 0.5));
  }

  // A box standing on its bottom face: the faces some camera position can see (never the bottom),
  // pushed forward until clear of the cameras.
  void box(const Box& b, double texel, int tex) {
    const Vec3 up = -frame_.down;
    const Vec3 ax = std::cos(b.yaw) * frame_.right + std::sin(b.yaw) * frame_.fwd;
    const Vec3 az = -std::sin(b.yaw) * frame_.right + std::cos(b.yaw) * frame_.fwd;
    const Vec3 c = frame_.point(b.x, b.bottom - 0.5 * b.h, b.z);
    struct Face {
      const char* tag;
      Vec3 normal;
      double offset, su, sv;
    };
    const Face faces[] = {{"front", -az, 0.5 * b.d, b.w, b.h},
                          {"back", az, 0.5 * b.d, b.w, b.h},
                          {"left", -ax, 0.5 * b.w, b.d, b.h},
                          {"right", ax, 0.5 * b.w, b.d, b.h},
                          {"top", up, 0.5 * b.h, b.w, b.d}};
    std::vector<Plane> group;
    for (const Face& f : faces) {
      Plane p;
      p.name = b.name + "_" + f.tag;
      p.center = c + f.offset * f.normal;
      if (f.normal.dot(up) > 0.5) {
        p.u = ax, p.v = az;
      } else {
        // Upright and not mirrored when seen from outside.
        p.u = f.normal.cross(frame_.down), p.v = frame_.down;
      }
      p.size_u = f.su, p.size_v = f.sv, p.texel = texel, p.texture = tex;
      bool seen = false;
      for (const Vec3& x : cams_) seen = seen || (x - p.center).dot(f.normal) > 0;
      if (seen) group.push_back(p);
    }
    addClear(group, frame_.fwd);
  }

  Scene finish() { return std::move(scene_); }

 private:
  double clearance(const std::vector<Plane>& group) const {
    double d = std::numeric_limits<double>::infinity();
    for (const Plane& p : group)
      for (const Vec3& x : cams_) d = std::min(d, rectDistance(p, x));
    return d;
  }

  void addClear(std::vector<Plane>& group, const Vec3& push) {
    for (int it = 0; it < 400 && clearance(group) < kMinClearance; ++it)
      for (Plane& p : group) p.center += 0.05 * push;
    for (const Plane& p : group) scene_.planes.push_back(p);
  }

  ViewFrame frame_;
  std::vector<Vec3> cams_;
  Rng rng_;
  Vec3 lo_, hi_;
  Scene scene_;
};

Scene planarScene(SceneBuilder& sb) {
  // As the shared ESIM sequence: 4 m x 3 m at 1 m, 2.5 mm texels (half a pixel at 1 m), blur 1 texel.
  const int tex = sb.texture("mix", 4.0, 3.0, 0.0025, 1.0);
  sb.rect("poster", {0, 0, 1.0}, {1, 0, 0}, {0, 1, 0}, 4.0, 3.0, 0.0025, tex, {0, 0, 1});
  return sb.finish();
}

Scene roomScene(SceneBuilder& sb) {
  Rng& r = sb.rng();
  const Vec3 lo = sb.lo(), hi = sb.hi();
  const double xl = lo.x() - r.uniform(2.2, 2.8), xr = hi.x() + r.uniform(2.2, 2.8);
  const double floor_y = hi.y() + 1.3, ceil_y = lo.y() - 1.5;
  const double z_back = std::max(r.uniform(5.5, 6.5), hi.z() + 3.0), z_behind = lo.z() - 2.0;
  const double xm = 0.5 * (xl + xr), ym = 0.5 * (floor_y + ceil_y), zm = 0.5 * (z_back + z_behind);
  const double W = xr - xl, H = floor_y - ceil_y, D = z_back - z_behind;

  // Walls: texels of ~1.5 px at their typical distance, each wall its own kind of texture.
  const double t_back = SceneBuilder::texelFor(z_back, 1.5), t_side = 0.02, t_floor = 0.025, t_behind = 0.025;
  sb.texturedRect("back_wall", {xm, ym, z_back}, {1, 0, 0}, {0, 1, 0}, W, H, t_back, "mix", {0, 0, 1});
  sb.texturedRect("left_wall", {xl, ym, zm}, {0, 0, 1}, {0, 1, 0}, D, H, t_side, "bricks", {-1, 0, 0});
  sb.texturedRect("right_wall", {xr, ym, zm}, {0, 0, -1}, {0, 1, 0}, D, H, t_side, "noise", {1, 0, 0});
  sb.texturedRect("floor", {xm, floor_y, zm}, {1, 0, 0}, {0, 0, 1}, W, D, t_floor, "checker", {0, 1, 0});
  sb.texturedRect("ceiling", {xm, ceil_y, zm}, {1, 0, 0}, {0, 0, -1}, W, D, t_floor, "blobs", {0, -1, 0});
  sb.texturedRect("wall_behind", {xm, ym, z_behind}, {-1, 0, 0}, {0, 1, 0}, W, H, t_behind, "stripes",
                  {0, 0, -1});

  // Boxes on the floor at 1.8-4.2 m; the tall one straddles the optical axis (its top above the
  // camera) and the small one stands on box1, so boxes occlude each other and the walls.
  const double deg = std::numbers::pi / 180.0;
  std::vector<Box> boxes = {
      {"box0", -0.9, 1.8, floor_y, 0.6, 0.7, 0.5, 0},
      {"box1", 0.7, 2.3, floor_y, 0.5, 1.0, 0.5, 0},
      {"box2", -0.15, 3.2, floor_y, 0.8, floor_y + 0.35, 0.6, 0},
      {"box3", 1.4, 3.8, floor_y, 0.7, 0.5, 0.7, 0},
      {"box4", -1.5, 4.2, floor_y, 0.6, 1.2, 0.6, 0},
  };
  const char* kinds[] = {"noise", "blobs", "mix", "checker", "stripes", "bricks"};
  int k = 0;
  for (Box& b : boxes) {
    b.x += r.uniform(-0.12, 0.12), b.z += r.uniform(-0.2, 0.2);
    b.w *= r.uniform(0.85, 1.15), b.h *= r.uniform(0.85, 1.15), b.d *= r.uniform(0.85, 1.15);
    b.yaw = r.uniform(-20, 20) * deg;
  }
  Box top{"box5", boxes[1].x, boxes[1].z, floor_y - boxes[1].h,
          0.3,    0.3,        0.3,        boxes[1].yaw + r.uniform(-15, 15) * deg};
  boxes.push_back(top);
  for (const Box& b : boxes) {
    sb.texturedBox(b, kinds[k++ % 6]);
  }
  return sb.finish();
}

Scene deskScene(SceneBuilder& sb) {
  Rng& r = sb.rng();
  const Vec3 lo = sb.lo(), hi = sb.hi();
  const double desk_y = hi.y() + 0.45, floor_y = desk_y + 0.75;
  const double z_wall = std::max(r.uniform(3.5, 4.5), hi.z() + 2.5);
  const double desk_x0 = lo.x() - 0.8, desk_x1 = hi.x() + 0.8, desk_z0 = lo.z() - 0.3, desk_z1 = hi.z() + 1.3;

  // Far wall and floor large enough to fill the view behind the desk.
  const double wall_w = 9.0 + (hi.x() - lo.x()), wall_h = 5.0;
  const double t_wall = SceneBuilder::texelFor(z_wall, 1.5);
  sb.texturedRect("far_wall", {0.5 * (lo.x() + hi.x()), floor_y - 0.5 * wall_h, z_wall}, {1, 0, 0}, {0, 1, 0},
                  wall_w, wall_h, t_wall, "mix", {0, 0, 1});
  const double floor_z0 = lo.z() - 1.0;
  sb.texturedRect("floor", {0.5 * (lo.x() + hi.x()), floor_y, 0.5 * (floor_z0 + z_wall)}, {1, 0, 0},
                  {0, 0, 1}, wall_w, z_wall - floor_z0, 0.02, "checker", {0, 1, 0});
  const double t_desk = SceneBuilder::texelFor(1.0, 1.0);  // seen from ~1 m on
  sb.texturedRect("desk", {0.5 * (desk_x0 + desk_x1), desk_y, 0.5 * (desk_z0 + desk_z1)}, {1, 0, 0},
                  {0, 0, 1}, desk_x1 - desk_x0, desk_z1 - desk_z0, t_desk, "noise", {0, 1, 0});

  // Objects at 0.5-0.9 m on the desk; the "monitor" covers the optical axis and rises above it.
  const double deg = std::numbers::pi / 180.0;
  std::vector<Box> objects = {
      {"monitor", 0.05, 0.9, desk_y, 0.5, desk_y + 0.1, 0.06, 0},
      {"obj1", -0.35, 0.55, desk_y, 0.15, 0.3, 0.15, 0},
      {"obj2", 0.32, 0.5, desk_y, 0.12, 0.35, 0.12, 0},
      {"obj3", -0.2, 0.75, desk_y, 0.22, 0.25, 0.16, 0},
      {"obj4", 0.5, 0.8, desk_y, 0.2, 0.4, 0.25, 0},
  };
  const char* kinds[] = {"mix", "blobs", "stripes", "checker", "bricks"};
  int k = 0;
  for (Box& b : objects) {
    const bool monitor = k == 0;
    b.x += r.uniform(-0.05, 0.05), b.z += r.uniform(-0.08, 0.08);
    b.w *= r.uniform(0.85, 1.15), b.d *= r.uniform(0.85, 1.15);
    if (!monitor) b.h *= r.uniform(0.85, 1.15);
    b.yaw = r.uniform(-1, 1) * (monitor ? 10 : 25) * deg;
    sb.texturedBox(b, kinds[k++ % 5]);
  }
  return sb.finish();
}

// A courtyard seen from standing height, for the sensitivity studies (the paper's "building-like
// scenes"): a facade 11-14 m ahead, side facades receding from 4 m to it, the ground, and pillars and a
// kiosk at 4-8 m. Depths span 4-14 m with the median several metres away.
Scene buildingScene(SceneBuilder& sb) {
  Rng& r = sb.rng();
  const Vec3 lo = sb.lo(), hi = sb.hi();
  const double ground_y = hi.y() + 1.6, height = 14.0, top_y = ground_y - height;
  const double z_far = std::max(r.uniform(11.0, 14.0), hi.z() + 8.0), z_near = lo.z() - 2.0;
  const double xl = lo.x() - r.uniform(4.0, 5.0), xr = hi.x() + r.uniform(4.0, 5.0);
  const double xm = 0.5 * (xl + xr), ym = 0.5 * (ground_y + top_y), zm = 0.5 * (z_far + z_near);
  const double W = xr - xl, D = z_far - z_near;
  const double t_far = SceneBuilder::texelFor(z_far, 1.5), t_side = SceneBuilder::texelFor(7.0, 1.5);
  sb.texturedRect("far_facade", {xm, ym, z_far}, {1, 0, 0}, {0, 1, 0}, W, height, t_far, "bricks", {0, 0, 1});
  sb.texturedRect("left_facade", {xl, ym, zm}, {0, 0, 1}, {0, 1, 0}, D, height, t_side, "mix", {-1, 0, 0});
  sb.texturedRect("right_facade", {xr, ym, zm}, {0, 0, -1}, {0, 1, 0}, D, height, t_side, "stripes",
                  {1, 0, 0});
  sb.texturedRect("ground", {xm, ground_y, zm}, {1, 0, 0}, {0, 0, 1}, W, D, 0.04, "noise", {0, 1, 0});
  const double deg = std::numbers::pi / 180.0;
  std::vector<Box> boxes = {{"pillar0", -2.2, 4.5, ground_y, 0.5, 4.0, 0.5, 0},
                            {"pillar1", 2.4, 6.0, ground_y, 0.5, 4.0, 0.5, 0},
                            {"kiosk", 0.4, 8.0, ground_y, 2.0, 2.6, 1.4, 0}};
  const char* kinds[] = {"checker", "blobs", "mix"};
  int k = 0;
  for (Box& b : boxes) {
    b.x += r.uniform(-0.3, 0.3), b.z += r.uniform(-0.5, 0.5), b.yaw = r.uniform(-20, 20) * deg;
    sb.texturedBox(b, kinds[k++ % 3]);
  }
  return sb.finish();
}

}  // namespace

const char* presetNames() { return "planar, room, desk, building"; }

Scene makePreset(const std::string& name, const Motion& motion, std::uint64_t seed) {
  std::vector<Vec3> cams;
  cams.reserve(motion.samples().size());
  for (const StampedPose& p : motion.samples()) cams.push_back(p.T_w_c.translation());
  const ViewFrame frame = viewFrame(cams, motion);
  SceneBuilder sb(frame, std::move(cams), seed);
  if (name == "planar") return planarScene(sb);
  if (name == "room") return roomScene(sb);
  if (name == "desk") return deskScene(sb);
  if (name == "building") return buildingScene(sb);
  throw std::invalid_argument("unknown preset '" + name + "' (known: " + presetNames() + ")");
}

}  // namespace eds::sim
