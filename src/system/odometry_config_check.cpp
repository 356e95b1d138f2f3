// Kept apart from the configuration I/O: the checks use the front-end's own validation, which the
// readers' fuzz build (configuration I/O, no pipeline) does not link.
#include <stdexcept>

#include "system/odometry_config_io.hpp"

namespace eds {

void validateOdometryConfig(const OdometryConfig& cfg, const CameraModel& camera) {
  cfg.event_frame.validate();
  cfg.deblur.validate();
  if (camera.width <= 0 || camera.height <= 0)
    throw std::invalid_argument("Odometry: the camera's sensor size is unknown");
  if (!(cfg.stream.max_frame_wait_s >= 0) || cfg.stream.max_pending_frames < 0)
    throw std::invalid_argument(
        "Odometry: stream.max_frame_wait_s and stream.max_pending_frames must not be negative");
  if (!(cfg.event_anchor_max_gap_s >= 0) || !(cfg.event_anchor_max_interval_s >= 0))
    throw std::invalid_argument("Odometry: event_anchor_max_interval_s and max_gap_s must not be negative");
  if (!(cfg.buffered_max_mb > 0))
    throw std::invalid_argument("Odometry: buffered_max_mb must be > 0, got " +
                                std::to_string(cfg.buffered_max_mb));
  if (!(cfg.buffered_before_reference_s >= 0))
    throw std::invalid_argument("Odometry: buffered_before_reference_s must not be negative, got " +
                                std::to_string(cfg.buffered_before_reference_s));
  if (!(cfg.frame_cv_min_distance >= 0) || !(cfg.frame_tracker.min_step >= 0) ||
      !(cfg.bootstrap.tracker.min_step >= 0))
    throw std::invalid_argument(
        "Odometry: frame_cv_min_distance and the frame trackers' min_step must not be negative");
  if (!(cfg.feature_start.min_interval_s >= 0) ||
      !(cfg.feature_start.max_rmse_ratio > 0 && cfg.feature_start.max_rmse_ratio <= 1))
    throw std::invalid_argument(
        "Odometry: feature_start.min_interval_s must not be negative and max_rmse_ratio must be in (0, 1]");
  if (!(cfg.frame_tracker.min_gain > 0) || !(cfg.bootstrap.tracker.min_gain > 0))
    throw std::invalid_argument("Odometry: the frame trackers' min_gain must be > 0");
  const RecoveryConfig& r = cfg.recovery;
  const RelocalizerConfig& rl = r.relocalizer;
  if (!(r.gap_s > 0) || r.failed_frames < 1 || !(r.max_refinement > 0) || r.new_map_after_frames < 1 ||
      !(r.new_map_after_s >= 0) || !(r.backfill_s >= 0))
    throw std::invalid_argument(
        "Odometry: recovery.gap_s and max_refinement must be > 0, failed_frames and new_map_after_frames "
        ">= 1, new_map_after_s and backfill_s >= 0");
  if (rl.features < 4 || rl.min_inliers < 4 || rl.depth_radius_px < 1 || !(rl.ratio > 0 && rl.ratio <= 1) ||
      !(rl.ransac_px > 0) || !(rl.min_inlier_fraction >= 0 && rl.min_inlier_fraction <= 1))
    throw std::invalid_argument(
        "Odometry: recovery.relocalizer needs features and min_inliers >= 4 (a pose needs 4 points), "
        "depth_radius_px >= 1, ratio in (0, 1], ransac_px > 0, min_inlier_fraction in [0, 1]");
}

}  // namespace eds
