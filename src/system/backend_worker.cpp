#include "system/backend_worker.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iterator>
#include <utility>

#include "core/log.hpp"
#include "system/run_stats.hpp"

namespace eds {

BackendWorker::BackendWorker(const CameraModel& pinhole, const MappingConfig& mapping,
                             const BackendConfig& backend, bool threaded, StageClock* caller_clock,
                             int first_id, bool early_reference)
    : cam_(pinhole),
      mcfg_(mapping),
      window_(pinhole, backend),
      next_id_(first_id),
      submitted_id_(first_id),
      threaded_(threaded),
      early_reference_(threaded && early_reference),
      caller_clock_(caller_clock) {
  mcfg_.points.validate();
  if (threaded_) thread_ = std::thread([this] { run(); });
}

BackendWorker::~BackendWorker() {
  if (!threaded_) return;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  cv_.notify_all();
  thread_.join();
}

int BackendWorker::submit(KeyframeJob job) {
  const int id = submitted_id_++;
  if (!threaded_) {
    process(job);
    return id;
  }
  // The worker gets pixels of its own: cv::Mat's reference count lives in OpenCV's uninstrumented
  // library, so a buffer the caller keeps reading and the worker frees is a race to ThreadSanitizer.
  job.image = job.image.clone();
  {
    std::lock_guard<std::mutex> lock(mutex_);
    queue_.push_back(std::move(job));
  }
  cv_.notify_all();
  return id;
}

int BackendWorker::nextId() const { return next_id_; }

bool BackendWorker::busy() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return working_ || !queue_.empty();
}

void BackendWorker::waitIdle() {
  if (!threaded_) return;
  const ScopedStage waiting(caller_clock_, Stage::kWaiting);
  std::unique_lock<std::mutex> lock(mutex_);
  cv_.wait(lock, [this] { return !working_ && queue_.empty(); });
}

void BackendWorker::waitMapped() {
  if (!early_reference_) return waitIdle();
  const ScopedStage waiting(caller_clock_, Stage::kWaiting);
  std::unique_lock<std::mutex> lock(mutex_);
  cv_.wait(lock, [this] { return queue_.empty() && (!working_ || mapped_); });
}

void BackendWorker::finish() {
  if (!threaded_) {
    if (!finished_) finalSolve();
    finished_ = true;
    return;
  }
  const ScopedStage waiting(caller_clock_, Stage::kWaiting);
  std::unique_lock<std::mutex> lock(mutex_);
  finish_ = true;
  cv_.notify_all();
  cv_.wait(lock, [this] { return finished_; });
}

void BackendWorker::finalSolve() {
  const ScopedStage ba(threaded_ ? &thread_clock_ : caller_clock_, Stage::kBundleAdjustment);
  window_.optimize();
  window_.flush();
  std::lock_guard<std::mutex> lock(mutex_);
  publishRetired();
}

void BackendWorker::publishRetired() {
  std::vector<RetiredKeyframe> k = window_.takeRetiredKeyframes();
  retired_.insert(retired_.end(), std::make_move_iterator(k.begin()), std::make_move_iterator(k.end()));
}

std::vector<RetiredKeyframe> BackendWorker::takeRetired() {
  std::lock_guard<std::mutex> lock(mutex_);
  return std::exchange(retired_, {});
}

std::optional<TrackingReference> BackendWorker::takeReference() {
  std::lock_guard<std::mutex> lock(mutex_);
  std::optional<TrackingReference> out;
  out.swap(published_);
  return out;
}

void BackendWorker::run() {
  std::unique_lock<std::mutex> lock(mutex_);
  while (true) {
    cv_.wait(lock, [this] { return stop_ || !queue_.empty() || (finish_ && !finished_); });
    if (queue_.empty() && finish_ && !finished_) {
      working_ = true;
      lock.unlock();
      finalSolve();
      lock.lock();
      working_ = false;
      finished_ = true;
      cv_.notify_all();
      continue;
    }
    if (queue_.empty() && stop_) return;
    KeyframeJob job = std::move(queue_.front());
    queue_.pop_front();
    working_ = true;
    mapped_ = false;
    lock.unlock();
    process(job);  // only this thread touches the window while working_
    lock.lock();
    working_ = false;
    cv_.notify_all();
  }
}

void BackendWorker::process(KeyframeJob& job) {
  StageClock* clock = threaded_ ? &thread_clock_ : caller_clock_;
  const auto t0 = Clock::now();
  std::optional<ScopedStage> stage(std::in_place, clock, Stage::kMapping);
  Keyframe kf;
  setKeyframeImage(kf, job.image);
  std::vector<KeyframePoint>& pts = job.points;
  if (pts.empty()) {
    // Mapping: the new keyframe's selected pixels take their depth from the window's points.
    const std::vector<cv::Point> px = selectPointsOnIntensity(kf.image, mcfg_.points);
    const std::vector<ProjectedPoint> proj = projectPoints(window_.worldPoints(), job.T_w_kf, cam_);
    std::vector<double> rho = fillInverseDepth(px, proj, mcfg_.fill);
    if (mcfg_.epipolar_search && !proj.empty())
      searchDepths(kf.image, job.T_w_kf, job.a, job.b, px, proj, rho);
    for (std::size_t i = 0; i < px.size(); ++i) {
      const float I = kf.image.at<float>(px[i].y, px[i].x);
      if (!(rho[i] > 0) || I > mcfg_.max_intensity || I < mcfg_.min_intensity) continue;
      KeyframePoint kp;
      kp.u = static_cast<float>(px[i].x), kp.v = static_cast<float>(px[i].y);
      kp.inv_depth = rho[i];
      pts.push_back(kp);
    }
  }
  window_.addKeyframe(next_id_, job.t, job.T_w_kf, job.a, job.b, kf.image, pts);
  const double map_ms = msSince(t0);
  if (early_reference_) {
    TrackingReference pre = newestReference(next_id_, job.t, false);
    pre.preliminary = true;
    std::lock_guard<std::mutex> lock(mutex_);
    published_ = std::move(pre);
    mapped_ = true;
    cv_.notify_all();
  }
  stage.emplace(clock, Stage::kBundleAdjustment);
  const auto t1 = Clock::now();
  const BaStats st = window_.optimize();
  const double ba_ms = msSince(t1);
  stage.reset();
  if (logEnabled(LogLevel::kDebug))
    logf(LogLevel::kDebug,
         "kf %d t %.3f: %zu new points, window %d kf %d points, rmse %.4f -> %.4f, %d it, %d outliers",
         next_id_, toSeconds(job.t), pts.size(), window_.size(), window_.numPoints(), st.initial_rmse,
         st.final_rmse, st.iterations, st.outliers_removed);
  TrackingReference ref = newestReference(next_id_++, job.t);
  std::lock_guard<std::mutex> lock(mutex_);
  timings_.mapping_ms.push_back(map_ms);
  timings_.ba_ms.push_back(ba_ms);
  timings_.window_points.push_back(window_.numPoints());
  published_ = std::move(ref);
  publishRetired();
}

TrackingReference BackendWorker::newestReference(int id, TimeNs t, bool with_new_points) const {
  TrackingReference ref;
  ref.id = id;
  const BaFrame& nf = window_.newest();
  ref.kf.id = id;
  ref.kf.t = t;
  ref.kf.T_w_kf = nf.T_w_c;
  ref.kf.image = nf.image;
  ref.kf.points = window_.pointsInNewest(with_new_points);
  ref.a = nf.a, ref.b = nf.b;
  return ref;
}

// Inverse depths of a new keyframe's pixels by epipolar search in the newest and the oldest keyframe of
// the window, over the range of the projected map's inverse depths (widened); where neither keyframe
// gives a baseline, the filled value stays; where the search fails or the two disagree, the pixel gets
// no depth.
void BackendWorker::searchDepths(const cv::Mat& img, const SE3& T_w_new, double a, double b,
                                 const std::vector<cv::Point>& px, const std::vector<ProjectedPoint>& proj,
                                 std::vector<double>& rho) const {
  std::vector<double> r;
  for (const ProjectedPoint& p : proj) r.push_back(p.inv_depth);
  std::sort(r.begin(), r.end());
  const double lo = 0.5 * r[r.size() / 50], hi = 2.0 * r[r.size() - 1 - r.size() / 50];
  const SearchFrame host{&img, T_w_new, a, b};
  const auto& fr = window_.frames();
  std::vector<std::vector<EpipolarMatch>> m;
  for (std::size_t k : {fr.size() - 1, std::size_t{0}}) {
    m.push_back(
        epipolarSearch(host, {&fr[k].image, fr[k].T_w_c, fr[k].a, fr[k].b}, cam_, px, lo, hi, mcfg_.search));
    if (fr.size() == 1) break;
  }
  for (std::size_t i = 0; i < px.size(); ++i) {
    const EpipolarMatch* best = nullptr;
    bool conflict = false, baseline = false;
    for (const auto& mk : m) {
      baseline = baseline || mk[i].line_px >= mcfg_.search.min_line_px;
      if (!(mk[i].inv_depth > 0)) continue;
      if (best && std::abs(best->inv_depth - mk[i].inv_depth) >
                      mcfg_.search_max_disagreement * std::max(best->inv_depth, mk[i].inv_depth))
        conflict = true;
      if (!best || mk[i].line_px > best->line_px) best = &mk[i];
    }
    if (best && !conflict)
      rho[i] = best->inv_depth;
    else if (baseline)
      rho[i] = 0;
  }
}

}  // namespace eds
