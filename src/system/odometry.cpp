#include "system/odometry.hpp"

#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <deque>
#include <functional>
#include <future>
#include <limits>
#include <optional>
#include <stdexcept>
#include <unordered_map>
#include <utility>
#include <vector>

#include "core/error.hpp"
#include "core/undistorter.hpp"
#include "frontend/exposure_estimate.hpp"
#include "system/event_frame_producer.hpp"
#include "system/exposure_events.hpp"
#include "system/odometry_config_io.hpp"
#include "system/odometry_core.hpp"
#include "system/run_stats.hpp"

namespace eds {

namespace {

double peakRssMb() {
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  return ru.ru_maxrss / 1024.0;  // kB on Linux
}

}  // namespace

// The stream merge in front of the core (StreamConfig), and the listener's notifications.
class Odometry::Impl {
 public:
  Impl(const CameraModel& camera, const OdometryConfig& cfg, OdometryListener* listener)
      : wall0_(Clock::now()),
        cfg_(validated(cfg, camera)),
        listener_(listener),
        core_(camera, cfg_, res_, clock_),
        producer_(core_.undistorter(), cfg_.event_frame, cfg_.flicker_filter,
                  cfg_.use_events && cfg_.stream.event_thread, &clock_) {
    if (listener_)
      core_.setRetiredSink([this](const RetiredKeyframe& k) { return listener_->onKeyframeRetired(k); });
    if (cfg_.use_events && cfg_.deblur.exposure_s > 0) {
      exposures_.emplace(fromSeconds(cfg_.deblur.exposure_s));
      res_.exposure_s = cfg_.deblur.exposure_s;
      res_.deblurred = true;
    } else if (const CameraModel& raw = core_.undistorter().raw();
               cfg_.use_events && cfg_.deblur.exposure_s == 0 && cfg_.deblur.estimate &&
               raw.width * raw.height <= ExposureEstimator::kMaxWidth * ExposureEstimator::kMaxHeight) {
      estimator_.emplace(cv::Size(raw.width, raw.height), cfg_.deblur.contrast);
      // Events are kept from the start as for the longest exposure, so that the frames after the
      // estimate find theirs whatever the chunks they came in; the frames before it are not deblurred.
      exposures_.emplace(fromSeconds(ExposureEstimator::kLongestExposureSeconds));
      keeps_longest_ = true;
    }
  }

  void addEvents(const EventArray& ev, std::size_t begin, std::size_t end) {
    const ScopedStage api(&clock_, Stage::kUnaccounted);
    checkOpen();
    if (!cfg_.use_events) return;
    end = std::min(end, ev.size());
    std::optional<ScopedStage> intake(std::in_place, &clock_, Stage::kEventIntake);
    const int w = core_.undistorter().raw().width, h = core_.undistorter().raw().height;
    TimeNs prev = checked_t_;  // committed only when the whole chunk is valid
    for (std::size_t i = begin; i < end; ++i) {
      if (ev.t[i] < prev)
        throw std::invalid_argument("Odometry::addEvents: event " + std::to_string(events_in_ + i - begin) +
                                    " at t = " + std::to_string(ev.t[i]) +
                                    " ns is before the one before it (" + std::to_string(prev) + " ns)");
      if (ev.x[i] >= w || ev.y[i] >= h || (ev.p[i] != 1 && ev.p[i] != -1))
        throw std::invalid_argument("Odometry::addEvents: event " + std::to_string(events_in_ + i - begin) +
                                    " at pixel (" + std::to_string(ev.x[i]) + ", " + std::to_string(ev.y[i]) +
                                    ") polarity " + std::to_string(ev.p[i]) + " is outside the " +
                                    std::to_string(w) + "x" + std::to_string(h) + " sensor or not +-1");
      prev = ev.t[i];
    }
    checked_t_ = prev;
    events_in_ += end - begin;
    if (exposures_) exposures_->addEvents(ev, begin, end);
    if (estimator_) estimator_->addEvents(ev, begin, end);
    intake.reset();
    producer_.add(ev, begin, end, [this] { dispatch(false); });
  }

  void addFrame(TimeNs t, const cv::Mat& gray8, TimeNs exposure) {
    const ScopedStage api(&clock_, Stage::kUnaccounted);
    checkOpen();
    const cv::Size size(core_.undistorter().raw().width, core_.undistorter().raw().height);
    if (gray8.empty() || gray8.type() != CV_8UC1 || gray8.size() != size)
      throw std::invalid_argument("Odometry::addFrame: frame at t = " + std::to_string(t) +
                                  " ns is not an 8-bit gray image of the sensor's size " +
                                  std::to_string(size.width) + "x" + std::to_string(size.height));
    if (has_frame_in_ && t <= last_frame_in_)
      throw std::invalid_argument("Odometry::addFrame: frame at t = " + std::to_string(t) +
                                  " ns is not after the previous frame (" + std::to_string(last_frame_in_) +
                                  " ns)");
    if (exposure < 0)
      throw std::invalid_argument("Odometry::addFrame: frame at t = " + std::to_string(t) +
                                  " ns has a negative exposure (" + std::to_string(exposure) + " ns)");
    has_frame_in_ = true;
    last_frame_in_ = t;
    {
      const ScopedStage prep(&clock_, Stage::kFramePreparation);
      // A recorded exposure longer than the events are kept for is not used.
      const TimeNs recorded = recordedUsable(exposure) ? exposure : 0;
      frames_.push_back({t, gray8.clone(), recorded});
      if (exposures_) exposures_->addFrame(t, frames_.back().image, recorded);
    }
    dispatch(false);
  }

  const OdometryResult& finish() {
    const ScopedStage api(&clock_, Stage::kUnaccounted);
    checkOpen();
    finished_ = true;
    producer_.finish();
    dispatch(true);
    endExposures(std::numeric_limits<TimeNs>::max());
    core_.finish();
    reportRecordedExposure();
    res_.events_flicker_dropped = producer_.flickerDropped();
    res_.event_frames_shed = producer_.packetsPassed();
    res_.event_thread = producer_.threaded();
    if (res_.event_thread) res_.event_stages_s = producer_.threadStageSeconds();
    const ScopedStage results(&clock_, Stage::kResults);
    TimeNs last_t = core_.lastTime();
    if (!res_.events.empty()) last_t = std::max(last_t, res_.events.back().t);
    res_.sequence_s = has_first_ ? toSeconds(last_t - res_.first_t) : 0.0;
    res_.peak_rss_mb = peakRssMb();
    res_.stages_s = clock_.seconds();
    res_.wall_s = std::chrono::duration<double>(Clock::now() - wall0_).count();
    return res_;
  }

  const OdometryResult& result() const { return res_; }
  void setEventFrameStride(int k) {
    if (k < 1) throw std::invalid_argument("Odometry: event frame stride must be at least 1");
    producer_.setEvery(static_cast<std::size_t>(k));
  }
  OdometryResult takeResult() {
    if (!finished_) throw std::logic_error("Odometry: takeResult() before finish()");
    return std::exchange(res_, {});
  }

 private:
  struct PendingFrame {
    TimeNs t;
    cv::Mat image;
    TimeNs recorded;  // the frame's exposure as recorded, when one can be used; else 0
  };

  // Frames' own exposures are used unless one was given: with the events kept as for the longest.
  bool recordedUsable(TimeNs exposure) const {
    return exposure > 0 && keeps_longest_ && exposures_ &&
           exposure <= fromSeconds(ExposureEstimator::kLongestExposureSeconds);
  }

  static const OdometryConfig& validated(const OdometryConfig& cfg, const CameraModel& camera) {
    validateOdometryConfig(cfg, camera);
    return cfg;
  }

  void checkOpen() const {
    if (finished_) throw std::logic_error("Odometry: used after finish()");
  }

  // Processes waiting items in time order while the order is certain (or a wait ran out). With the
  // producer thread, what it has not built yet is unknown: an uncertain item waits like without it,
  // and before a wait runs out the producer finishes its queue, so that the same decision is taken.
  void dispatch(bool at_end) {
    producer_.take(efs_);
    while (!frames_.empty() || !efs_.empty()) {
      if (!frames_.empty() && !efs_.empty()) {
        if (frames_.front().t <= efs_.front().t)
          processFrame();
        else
          processEventFrame();
      } else if (!frames_.empty()) {
        const bool events_past = !cfg_.use_events || producer_.nextPacketStartsAtOrAfter(frames_.front().t);
        if (events_past && cfg_.use_events) {
          // The producer publishes a packet and where the next one starts together: packets it finished
          // since the take above (earlier than the frame) are there now, and go first.
          producer_.take(efs_);
          if (!efs_.empty()) continue;
        }
        if (!(at_end || events_past)) {
          if (frames_.size() <= static_cast<std::size_t>(cfg_.stream.max_pending_frames)) return;
          // What the producer builds or has built since the take above goes first where it is earlier
          // (asking idle() alone raced with a packet finished in between).
          producer_.drain(efs_);
          if (!efs_.empty()) continue;
        }
        processFrame();
      } else {
        const TimeNs t = efs_.front().t;
        const bool frame_past = has_frame_in_ && last_frame_in_ >= t;
        const TimeNs wait = fromSeconds(cfg_.stream.max_frame_wait_s);
        if (!(at_end || frame_past)) {
          if (checked_t_ - t <= wait) return;  // no wait can have run out
          if (!producer_.idle()) {
            producer_.drain(efs_);
            continue;
          }
          if (producer_.newestEvent() - t <= wait) return;
        }
        processEventFrame();
      }
      producer_.take(efs_);
    }
  }

  // Exposures that ended before the next item in the merged order (of frames already processed).
  void endExposures(TimeNs up_to) {
    if (!exposures_) return;
    exposures_->endExposures(up_to, last_frame_done_,
                             [this](TimeNs t, TimeNs exposure, bool recorded, const cv::Mat& raw,
                                    const EventArray& ev, std::size_t b, std::size_t e) {
                               // Once frames come with their exposures, only those are deblurred.
                               if (recorded_ ? recorded : !estimator_)
                                 core_.exposureEnded(t, exposure, raw, ev, b, e);
                             });
  }

  // Frames go to the exposure estimator until it has an estimate; the frames after it are deblurred
  // with it (when it is long enough to blur).
  void useExposureEstimate() {
    if (!estimator_->done()) return;
    res_.exposure_estimated = true;
    res_.exposure_pairs = estimator_->pairsScored();
    const double T = res_.exposure_s = estimator_->exposureSeconds();
    if (T >= cfg_.deblur.min_exposure_s && T > 0) {
      exposures_->setExposure(fromSeconds(T));
      res_.deblurred = true;
    } else {
      exposures_.reset();
    }
    estimator_.reset();
  }

  // A frame with its exposure recorded: no estimate is needed, and each such frame is deblurred with its
  // own exposure (the reported one is their median).
  void useRecordedExposure(TimeNs exposure) {
    estimator_.reset();
    recorded_ = true;
    res_.exposure_estimated = false;
    res_.exposure_recorded = res_.deblurred = true;
    recorded_s_.push_back(toSeconds(exposure));
  }

  // The median of the recorded exposures, once at the end (a sort per frame would grow with the run).
  void reportRecordedExposure() {
    if (recorded_s_.empty()) return;
    std::nth_element(recorded_s_.begin(), recorded_s_.begin() + recorded_s_.size() / 2, recorded_s_.end());
    res_.exposure_s = recorded_s_[recorded_s_.size() / 2];
  }

  void processFrame() {
    const PendingFrame f = std::move(frames_.front());
    frames_.pop_front();
    endExposures(f.t);
    if (!has_first_) has_first_ = true, res_.first_t = f.t;
    last_frame_done_ = f.t;
    if (f.recorded > 0) useRecordedExposure(f.recorded);
    // The exposure estimator scores its frame pairs on another thread while this one tracks the frame.
    // The tracking does not read the estimator's state, and nothing else runs here before the join, so
    // the outputs are those of scoring first.
    std::future<void> scoring;
    if (estimator_)
      scoring = std::async(std::launch::async, [this, &f] { estimator_->addFrame(f.t, f.image); });
    struct Join {  // also when the tracking throws
      std::future<void>& job;
      ~Join() {
        if (job.valid()) job.wait();
      }
    } join{scoring};
    core_.frame(f.t, f.image);
    if (scoring.valid()) {
      const ScopedStage stage(&clock_, Stage::kFramePreparation);
      scoring.get();
      useExposureEstimate();
    }
    notify();
  }

  void processEventFrame() {
    EventFrame ef = std::move(efs_.front());
    efs_.pop_front();
    endExposures(ef.t);
    // Before the first frame: nothing to track against yet (a recording's events before its frames).
    if (has_first_ && ef.t >= res_.first_t) {
      if (ef.t < last_frame_done_) {
        // A frame after it went ahead (the events stalled): too late to be tracked in order.
        res_.failures.push_back({ef.t, "event frame: arrived after a later frame was processed"});
      } else {
        core_.eventFrame(ef);
      }
      notify();
    }
    producer_.recycle(std::move(ef));
  }

  // Tells the listener what the last item produced.
  void notify() {
    if (!listener_) return;
    const ScopedStage stage(&clock_, Stage::kResults);
    if (res_.initialized && !told_init_) listener_->onInitialized(res_.init_t), told_init_ = true;
    FrameFrontend& odo = core_.frontend();
    // A new map segment has no reference until its bootstrap ends (id -1): nothing to tell then.
    if (res_.initialized && odo.referenceId() >= 0 && odo.referenceId() != told_kf_) {
      told_kf_ = odo.referenceId();
      listener_->onKeyframe({told_kf_, odo.reference().t, odo.T_w_kf(), odo.reference().points.size()});
    }
    for (; told_frames_ < res_.frames.size(); ++told_frames_)
      listener_->onFramePose(res_.frames[told_frames_], res_.frame_anchors[told_frames_].kf_id);
    for (; told_events_ < res_.events.size(); ++told_events_)
      listener_->onEventPose(res_.events[told_events_], res_.event_anchors[told_events_].kf_id);
    for (; told_failures_ < res_.failures.size(); ++told_failures_)
      listener_->onFailure(res_.failures[told_failures_]);
    for (told_segments_ = std::max<std::size_t>(told_segments_, 1); told_segments_ < res_.segments.size();
         ++told_segments_)
      listener_->onNewMapSegment(res_.segments[told_segments_]);
  }

  Clock::time_point wall0_;
  const OdometryConfig cfg_;
  OdometryListener* listener_;
  OdometryResult res_;
  StageClock clock_{Stage::kInput};  // the calling thread's
  OdometryCore core_;
  EventFrameProducer producer_;  // flicker filter, event buffer, event frames
  std::size_t events_in_ = 0;
  // The newest event checked (the waits measure from the newest the producer has processed, so that
  // they do not depend on the chunk size).
  TimeNs checked_t_ = std::numeric_limits<TimeNs>::min();
  std::deque<PendingFrame> frames_;
  bool keeps_longest_ = false;  // exposures_ keeps the events of the longest exposure estimated
  bool recorded_ = false;       // frames came with their exposures (those alone are deblurred)
  std::vector<double> recorded_s_;
  std::optional<ExposureEvents> exposures_;     // with the frames' exposure known (deblurring)
  std::optional<ExposureEstimator> estimator_;  // while the exposure is being estimated
  std::deque<EventFrame> efs_;
  bool has_frame_in_ = false, has_first_ = false, finished_ = false;
  TimeNs last_frame_in_ = 0, last_frame_done_ = std::numeric_limits<TimeNs>::min();
  bool told_init_ = false;
  int told_kf_ = -1;
  std::size_t told_frames_ = 0, told_events_ = 0, told_failures_ = 0, told_segments_ = 0;
};

Odometry::Odometry(const CameraModel& camera, const OdometryConfig& cfg, OdometryListener* listener)
    : impl_(std::make_unique<Impl>(camera, cfg, listener)) {}
Odometry::~Odometry() = default;
void Odometry::addEvents(const EventArray& events, std::size_t begin, std::size_t end) {
  impl_->addEvents(events, begin, end);
}
void Odometry::addFrame(TimeNs t, const cv::Mat& gray8, TimeNs exposure) {
  impl_->addFrame(t, gray8, exposure);
}
const OdometryResult& Odometry::finish() { return impl_->finish(); }
const OdometryResult& Odometry::result() const { return impl_->result(); }
OdometryResult Odometry::takeResult() { return impl_->takeResult(); }
void Odometry::setEventFrameStride(int k) { impl_->setEventFrameStride(k); }

}  // namespace eds
