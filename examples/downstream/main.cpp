// Builds an Odometry from the installed headers and feeds it a few synthetic frames; prints the
// version it was built against.
#include <cstdio>
#include <eds/system/odometry.hpp>
#include <eds/core/version.hpp>

int main() {
  eds::CameraModel cam;
  cam.width = 240, cam.height = 180, cam.fx = cam.fy = 200, cam.cx = 120, cam.cy = 90;
  eds::OdometryConfig cfg;
  cfg.use_events = false;
  eds::Odometry odo(cam, cfg);
  for (int i = 0; i < 3; ++i) odo.addFrame(eds::fromSeconds(0.05 * i), cv::Mat(180, 240, CV_8UC1, cv::Scalar(100)));
  const eds::OdometryResult& r = odo.finish();
  std::printf("eds %s: %zu frames in, initialized %d\n", eds::versionString().c_str(), r.frames_in, r.initialized);
  return r.frames_in == 3 ? 0 : 1;
}
