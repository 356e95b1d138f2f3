#include "sim/simulator.hpp"

#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace eds::sim {

CameraModel defaultCamera(int width, int height) {
  CameraModel cam;
  cam.width = width, cam.height = height;
  cam.fx = cam.fy = 0.832 * width;
  cam.cx = (width - 1) / 2.0, cam.cy = (height - 1) / 2.0;
  return cam;
}

Simulator::Simulator(const Scene& scene, const CameraModel& camera, const Motion& motion, SimConfig cfg)
    : scene_(scene), camera_(camera), motion_(motion), cfg_(cfg), renderer_(scene, camera, cfg.render) {
  if (cfg.fps < 0 || cfg.exposure_s < 0 || cfg.render_hz < 0 || !(cfg.max_px_per_step > 0))
    throw std::invalid_argument("simulator: fps, exposure and render rate must be >= 0");
}

void Simulator::refreshSamplePoints(const SE3& T_w_c) {
  // A sparse grid of scene points is enough to bound the optical flow of the whole image; its rays
  // are intersected here (a full render would cost as much as a step).
  sample_points_w_.clear();
  const int step = 8;
  for (int y = 0; y < camera_.height; y += step) {
    for (int x = 0; x < camera_.width; x += step) {
      const Vec3 ray_c = camera_.unproject(Vec2(x, y));
      const Vec3 d_w = T_w_c.so3() * ray_c;
      const Vec3& o = T_w_c.translation();
      double best = std::numeric_limits<double>::infinity();
      for (const Plane& pl : scene_.planes) {
        const Vec3 n = pl.normal();
        const double den = n.dot(d_w);
        if (std::abs(den) < 1e-12) continue;
        const double s = n.dot(pl.center - o) / den;
        if (!(s > 1e-3) || s >= best) continue;
        const Vec3 X = o + s * d_w;
        if (!scene_.mirror_outside && (std::abs((X - pl.center).dot(pl.u)) > 0.5 * pl.size_u ||
                                       std::abs((X - pl.center).dot(pl.v)) > 0.5 * pl.size_v))
          continue;
        best = s;
      }
      if (std::isfinite(best)) sample_points_w_.push_back(o + best * d_w);
    }
  }
}

double Simulator::maxDisplacement(const SE3& T_w_a, const SE3& T_w_b) const {
  const SE3 T_a_w = T_w_a.inverse(), T_b_w = T_w_b.inverse();
  double worst = 0;
  for (const Vec3& p_w : sample_points_w_) {
    const Vec3 pa = T_a_w * p_w, pb = T_b_w * p_w;
    if (pa.z() < 1e-3 || pb.z() < 1e-3) return 1e9;
    // Pinhole flow is a tight enough bound: distortion changes it by a few percent at most here.
    const double dx = camera_.fx * (pb.x() / pb.z() - pa.x() / pa.z());
    const double dy = camera_.fy * (pb.y() / pb.z() - pa.y() / pa.z());
    worst = std::max(worst, std::hypot(dx, dy));
  }
  return worst;
}

void Simulator::renderFrame(TimeNs t, SimSink& sink) {
  cv::Mat intensity, depth;
  renderer_.render(motion_.pose(t), intensity, &depth);
  if (cfg_.exposure_s > 0) {
    // Motion blur: the mean of renders spread over the exposure, centred on the frame time.
    constexpr int kSub = 8;
    cv::Mat acc = cv::Mat::zeros(intensity.size(), CV_32F), sub;
    for (int k = 0; k < kSub; ++k) {
      const double off = ((k + 0.5) / kSub - 0.5) * cfg_.exposure_s;
      renderer_.render(motion_.pose(t + static_cast<TimeNs>(off * 1e9)), sub);
      acc += sub;
    }
    intensity = acc / kSub;
  }
  sink.onFrame(t, intensity, depth);
}

SimStats Simulator::run(TimeNs t0, TimeNs t1, SimSink& sink) {
  if (t1 <= t0) throw std::invalid_argument("simulator: empty time span");
  const auto wall0 = std::chrono::steady_clock::now();
  SimStats stats;
  EventGenerator gen(camera_.width, camera_.height, cfg_.events);
  cv::Mat intensity, log_image;
  renderer_.render(motion_.pose(t0), intensity);
  toLogImage(intensity, cfg_.events.log_eps, cfg_.quantize_8bit, log_image);
  gen.reset(log_image, t0);
  ++stats.renders;
  const auto frame_period = cfg_.fps > 0 ? static_cast<TimeNs>(std::llround(1e9 / cfg_.fps)) : 0;
  TimeNs next_frame = t0;
  if (frame_period > 0) {
    renderFrame(t0, sink);
    ++stats.frames;
    next_frame = t0 + frame_period;
  }
  const auto fixed_step = cfg_.render_hz > 0 ? static_cast<TimeNs>(std::llround(1e9 / cfg_.render_hz)) : 0;
  const auto min_step = static_cast<TimeNs>(cfg_.min_step_s * 1e9);
  const auto max_step = static_cast<TimeNs>(cfg_.max_step_s * 1e9);
  TimeNs t = t0, dt = min_step * 10;
  EventArray batch;
  SE3 T_w_c = motion_.pose(t0);
  refreshSamplePoints(T_w_c);
  while (t < t1) {
    TimeNs step;
    if (fixed_step > 0) {
      step = fixed_step;
    } else {
      // Grow the step while the flow stays under the limit, shrink it when it exceeds it.
      step = std::min(max_step, dt * 2);
      while (step > min_step) {
        const double d = maxDisplacement(T_w_c, motion_.pose(t + step));
        if (d <= cfg_.max_px_per_step) break;
        step = std::max(min_step, static_cast<TimeNs>(step * std::max(0.3, 0.9 * cfg_.max_px_per_step / d)));
      }
      dt = step;
    }
    TimeNs t_next = std::min(t + step, t1);
    if (frame_period > 0 && next_frame > t && next_frame < t_next) t_next = next_frame;  // land on frames
    T_w_c = motion_.pose(t_next);
    renderer_.render(T_w_c, intensity);
    toLogImage(intensity, cfg_.events.log_eps, cfg_.quantize_8bit, log_image);
    batch.clear();
    gen.step(log_image, t_next, batch);
    ++stats.renders;
    stats.events += batch.size();
    if (!batch.empty()) sink.onEvents(batch);
    t = t_next;
    if (frame_period > 0 && t == next_frame && t <= t1) {
      renderFrame(t, sink);
      ++stats.frames;
      next_frame += frame_period;
    }
    if (fixed_step == 0 && stats.renders % 4 == 0) refreshSamplePoints(T_w_c);
  }
  stats.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  return stats;
}

}  // namespace eds::sim
