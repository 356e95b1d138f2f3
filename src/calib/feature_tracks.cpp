#include "calib/feature_tracks.hpp"

#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>
#include <stdexcept>

namespace eds {

void FeatureTrackConfig::validate() const {
  auto need = [](bool ok, const char* what) {
    if (!ok) throw std::invalid_argument(std::string("feature tracks: ") + what);
  };
  need(max_features > 0, "max_features must be positive");
  need(quality > 0 && quality < 1, "quality must be in (0, 1)");
  need(min_distance_px >= 0, "min_distance_px must be >= 0");
  need(window_px >= 5 && window_px % 2 == 1, "window_px must be odd and >= 5");
  need(pyramid_levels >= 0 && pyramid_levels <= 6, "pyramid_levels must be in [0, 6]");
  need(max_fb_error_px > 0, "max_fb_error_px must be positive");
  need(border_px >= 0, "border_px must be >= 0");
  need(min_length >= 2, "min_length must be >= 2");
}

namespace {

bool insideBorder(const cv::Point2f& p, const cv::Size& size, int border) {
  return p.x >= border && p.y >= border && p.x <= size.width - 1 - border && p.y <= size.height - 1 - border;
}

}  // namespace

std::vector<FeatureTrack> trackFeatures(const std::vector<cv::Mat>& frames, const FeatureTrackConfig& cfg) {
  cfg.validate();
  std::vector<FeatureTrack> done;
  std::vector<FeatureTrack> live;
  std::vector<cv::Point2f> pts;  // live features' positions in the previous frame
  auto retire = [&](FeatureTrack&& t) {
    if (static_cast<int>(t.frames.size()) >= cfg.min_length) done.push_back(std::move(t));
  };
  const cv::Size win(cfg.window_px, cfg.window_px);
  const cv::TermCriteria stop(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 30, 0.01);
  cv::Mat prev;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const cv::Mat& cur = frames[i];
    if (cur.empty()) {
      for (auto& t : live) retire(std::move(t));
      live.clear();
      pts.clear();
      prev = cv::Mat();
      continue;
    }
    if (cur.type() != CV_8UC1) throw std::invalid_argument("feature tracks: frames must be 8-bit grayscale");
    if (!prev.empty() && cur.size() != prev.size())
      throw std::invalid_argument("feature tracks: frame " + std::to_string(i) + " changes the image size");
    if (!prev.empty() && !pts.empty()) {
      std::vector<cv::Point2f> fwd, back;
      std::vector<uchar> ok_f, ok_b;
      std::vector<float> err;
      cv::calcOpticalFlowPyrLK(prev, cur, pts, fwd, ok_f, err, win, cfg.pyramid_levels, stop);
      cv::calcOpticalFlowPyrLK(cur, prev, fwd, back, ok_b, err, win, cfg.pyramid_levels, stop);
      std::vector<FeatureTrack> kept;
      std::vector<cv::Point2f> kept_pts;
      const double fb2 = cfg.max_fb_error_px * cfg.max_fb_error_px;
      for (std::size_t j = 0; j < pts.size(); ++j) {
        const cv::Point2f d = back[j] - pts[j];
        if (ok_f[j] && ok_b[j] && d.dot(d) <= fb2 && insideBorder(fwd[j], cur.size(), cfg.border_px)) {
          live[j].frames.push_back(static_cast<int>(i));
          live[j].px.emplace_back(fwd[j].x, fwd[j].y);
          kept.push_back(std::move(live[j]));
          kept_pts.push_back(fwd[j]);
        } else {
          retire(std::move(live[j]));
        }
      }
      live = std::move(kept);
      pts = std::move(kept_pts);
    }
    // Top up with new corners away from the live ones.
    const int want = cfg.max_features - static_cast<int>(pts.size());
    if (want > 0) {
      cv::Mat mask(cur.size(), CV_8U, cv::Scalar(0));
      const int b = cfg.border_px;
      if (cur.cols > 2 * b && cur.rows > 2 * b)
        mask(cv::Rect(b, b, cur.cols - 2 * b, cur.rows - 2 * b)).setTo(255);
      for (const auto& p : pts) cv::circle(mask, p, static_cast<int>(cfg.min_distance_px), cv::Scalar(0), -1);
      std::vector<cv::Point2f> fresh;
      cv::goodFeaturesToTrack(cur, fresh, want, cfg.quality, cfg.min_distance_px, mask);
      if (!fresh.empty())
        cv::cornerSubPix(cur, fresh, cv::Size(3, 3), cv::Size(-1, -1),
                         cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 20, 0.01));
      for (const auto& p : fresh) {
        if (!insideBorder(p, cur.size(), cfg.border_px)) continue;
        FeatureTrack t;
        t.frames.push_back(static_cast<int>(i));
        t.px.emplace_back(p.x, p.y);
        live.push_back(std::move(t));
        pts.push_back(p);
      }
    }
    prev = cur;
  }
  for (auto& t : live) retire(std::move(t));
  return done;
}

}  // namespace eds
