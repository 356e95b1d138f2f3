#include "support/sim_event_frame_case.hpp"

#include <stdexcept>
#include <string>

#include "core/undistorter.hpp"
#include "frontend/point_selection.hpp"
#include "sim/presets.hpp"
#include "sim/simulator.hpp"

namespace eds {
namespace {

// Keeps every event and the frame rendered at the keyframe time.
struct Collect : sim::SimSink {
  explicit Collect(TimeNs t_kf) : t_kf(t_kf) {}
  void onEvents(const EventArray& e) override {
    for (std::size_t i = 0; i < e.size(); ++i) events.push_back(e.t[i], e.x[i], e.y[i], e.p[i]);
  }
  void onFrame(TimeNs t, const cv::Mat& intensity, const cv::Mat& depth) override {
    // Frame times are rounded to whole nanoseconds of the frame period: match within 0.1 ms.
    if (image.empty() && std::llabs(t - t_kf) < 100'000) {
      image = intensity.clone();
      depth_m = depth.clone();
      t_image = t;
    }
  }
  TimeNs t_kf;
  EventArray events;
  cv::Mat image, depth_m;
  TimeNs t_image = 0;
};

}  // namespace

SimEventFrameCase makeSimEventFrameCase(const SimEventFrameCaseConfig& cfg) {
  if (cfg.keyframe_time_s < 0 || !(cfg.event_frame_delay_s > 0) || cfg.num_events <= 0)
    throw std::invalid_argument("sim event-frame case: keyframe time >= 0, delay > 0 and N > 0 needed");
  SimEventFrameCase c;
  const double t_end = cfg.keyframe_time_s + cfg.event_frame_delay_s + 0.05;
  const sim::Motion motion(sim::handheldMotion(t_end, cfg.seed));
  sim::Scene scene = sim::makePreset("planar", motion, cfg.seed);  // a textured plane 1 m ahead
  for (auto& spec : scene.texture_specs) spec.blur_sigma = cfg.texture_blur_px;
  scene.loadTextures();
  c.cam.width = 240, c.cam.height = 180;
  c.cam.fx = c.cam.fy = 200;
  c.cam.cx = 119.5, c.cam.cy = 89.5;
  sim::SimConfig sc;
  // One frame at the start and, when later, one at the keyframe time.
  sc.fps = cfg.keyframe_time_s > 0 ? 1.0 / cfg.keyframe_time_s : 1.0;
  sc.render.supersample = 2;
  sc.events.C_pos = sc.events.C_neg = cfg.contrast;
  sc.events.hysteresis = cfg.hysteresis;
  Collect sink(motion.start() + fromSeconds(cfg.keyframe_time_s));
  sim::Simulator(scene, c.cam, motion, sc).run(motion.start(), motion.end(), sink);
  if (sink.image.empty()) throw std::runtime_error("sim event-frame case: no frame at the keyframe time");

  setKeyframeImage(c.kf, sink.image);
  for (const cv::Point& p : selectPoints(c.kf.grad_x, c.kf.grad_y, PointSelectionConfig{})) {
    const float z = sink.depth_m.at<float>(p.y, p.x);
    if (z > 0)
      c.kf.points.push_back({static_cast<float>(p.x), static_cast<float>(p.y),
                             c.kf.grad_x.at<float>(p.y, p.x), c.kf.grad_y.at<float>(p.y, p.x), 1.0 / z});
  }

  const Undistorter und(c.cam);
  EventFrameConfig efc;
  efc.num_events = cfg.num_events;
  efc.reversal_compensation = cfg.reversal_compensation;
  EventFrameBuilder builder(und, efc);
  const TimeNs t_centre = sink.t_image + fromSeconds(cfg.event_frame_delay_s);
  std::size_t centre = 0;
  while (centre < sink.events.size() && sink.events.t[centre] < t_centre) ++centre;
  const auto half = static_cast<std::size_t>(cfg.num_events / 2);
  if (centre < half || centre + half > sink.events.size())
    throw std::runtime_error("sim event-frame case: too few events around " +
                             std::to_string(toSeconds(t_centre) * 1e3) + " ms");
  c.total_events = sink.events.size();
  builder.build(sink.events, centre - half, c.ef);
  c.T_ef_kf_true = motion.pose(c.ef.t).inverse() * motion.pose(sink.t_image);
  return c;
}

SimCaseSolution trackSimCase(const SimEventFrameCase& c, const SE3& offset, int max_points) {
  EventTracker tracker(c.cam, {});
  tracker.setKeyframe(c.kf, max_points);
  SimCaseSolution s;
  SE3 T = offset * c.T_ef_kf_true;
  Vec6 nu = Vec6::Zero();
  s.first = tracker.track(c.ef, T, nu);
  s.second = tracker.track(c.ef, T, nu);
  s.T_ef_kf = T;
  s.rot_err_deg = (T * c.T_ef_kf_true.inverse()).so3().angle() * 180.0 / M_PI;
  s.trans_err_mm = (T.inverse().translation() - c.T_ef_kf_true.inverse().translation()).norm() * 1000.0;
  return s;
}

}  // namespace eds
