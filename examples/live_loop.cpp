// How a camera driver feeds eds: its event and frame callbacks (often two threads) push into one
// `eds::Odometry` under a mutex, and a listener receives the poses as they are produced. Here a
// recorded sequence, replayed at its own pace, stands in for the camera.
//   live_loop SEQUENCE
#include <chrono>
#include <cstdio>
#include <mutex>
#include <thread>

#include "io/sequence.hpp"
#include "system/odometry.hpp"

namespace {

// Called on the thread that pushed the data (inside addEvents / addFrame / finish).
struct PrintPoses : eds::OdometryListener {
  void onInitialized(eds::TimeNs t) override { std::printf("initialized at %.3f s\n", eds::toSeconds(t)); }
  void onEventPose(const eds::StampedPose& p, int kf) override {
    const eds::Vec3 x = p.T_w_c.translation();
    std::printf("event pose %.4f  % .4f % .4f % .4f  (keyframe %d)\n", eds::toSeconds(p.t), x.x(), x.y(), x.z(),
                kf);
  }
  void onKeyframe(const eds::KeyframeUpdate& k) override {
    std::printf("keyframe %d at %.3f s, %zu points\n", k.id, eds::toSeconds(k.t), k.points);
  }
  void onFailure(const eds::OdometryFailure& f) override {
    std::printf("failure at %.3f s: %s\n", eds::toSeconds(f.t), f.reason.c_str());
  }
};

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: live_loop SEQUENCE\n");
    return 2;
  }
  try {
    const eds::Sequence seq(argv[1]);
    PrintPoses listener;
    eds::Odometry odo(seq.camera(), eds::OdometryConfig{}, &listener);
    std::mutex mutex;  // the two driver threads below take turns in the Odometry
    const auto start = std::chrono::steady_clock::now();
    const eds::TimeNs t0 = seq.frames().empty() ? 0 : seq.frames().front().t;
    auto waitUntil = [&](eds::TimeNs t) {  // the camera delivers data at its own pace
      std::this_thread::sleep_until(start + std::chrono::nanoseconds(t - t0));
    };
    // The event callback: small packets as the sensor's USB transfers deliver them.
    std::thread events([&] {
      auto src = seq.openEvents();
      eds::EventArray packet;
      while (packet.clear(), src->read(packet, 2000) > 0) {
        waitUntil(packet.t.back());
        const std::lock_guard<std::mutex> lock(mutex);
        odo.addEvents(packet);
      }
    });
    // The frame callback: each frame once it is exposed and read out.
    std::thread frames([&] {
      for (std::size_t i = 0; i < seq.frames().size(); ++i) {
        const cv::Mat image = seq.loadFrame(i);
        waitUntil(seq.frames()[i].t);
        const std::lock_guard<std::mutex> lock(mutex);
        odo.addFrame(seq.frames()[i].t, image);
      }
    });
    events.join();
    frames.join();
    const eds::OdometryResult& r = odo.finish();
    std::printf("%zu event poses, %zu frame poses, %zu keyframes, %zu map points\n", r.events.size(),
                r.frames.size(), r.keyframes.size(), r.map.size());
    return r.initialized ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "live_loop: %s\n", e.what());
    return 1;
  }
}
