#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/calib3d.hpp>
#include <random>

#include "core/camera.hpp"
#include "core/undistorter.hpp"
#include "io/sequence.hpp"
#include "test_data.hpp"

namespace eds {
namespace {

CameraModel sliderLikeCamera() {
  // The ECD DAVIS240C calibration (also in ../shared/data/ecd_slider_depth/calib.txt).
  CameraModel c;
  c.width = 240, c.height = 180;
  c.fx = 335.419462958, c.fy = 335.352935612, c.cx = 129.924663379, c.cy = 99.1864303447;
  c.distortion = Distortion::kRadTan;
  c.k = {-0.138592767408, 0.0933736664192, -0.000335586987532, 0.000173720158228, 0.0};
  return c;
}

CameraModel fisheyeCamera() {
  CameraModel c;
  c.width = 346, c.height = 260;
  c.fx = 180.0, c.fy = 181.0, c.cx = 170.0, c.cy = 128.0;
  c.distortion = Distortion::kEquidistant;
  c.k = {0.05, -0.02, 0.004, -0.001, 0.0};
  return c;
}

void expectMatchesOpenCv(const CameraModel& cam) {
  const cv::Matx33d K(cam.fx, 0, cam.cx, 0, cam.fy, cam.cy, 0, 0, 1);
  std::vector<cv::Point2d> raw, ref;
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x) raw.emplace_back(x, y);
  // Many iterations: OpenCV's default of 5 fixed-point steps is itself not converged to 1e-3 px.
  const cv::TermCriteria crit(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 200, 1e-14);
  if (cam.distortion == Distortion::kEquidistant) {
    const cv::Vec4d D(cam.k[0], cam.k[1], cam.k[2], cam.k[3]);
    cv::fisheye::undistortPoints(raw, ref, K, D, cv::noArray(), K);
  } else {
    const cv::Matx<double, 1, 5> D(cam.k[0], cam.k[1], cam.k[2], cam.k[3], cam.k[4]);
    cv::undistortPoints(raw, ref, K, D, cv::noArray(), K, crit);
  }
  // The camera model, and the event look-up table every event goes through (float, one per raw pixel).
  const Undistorter und(cam);
  double worst = 0, worst_lut = 0;
  for (std::size_t i = 0; i < raw.size(); ++i) {
    const Vec2 u = cam.undistortPixel(Vec2(raw[i].x, raw[i].y));
    worst = std::max(worst, (u - Vec2(ref[i].x, ref[i].y)).norm());
    const cv::Point2f l = und.eventLut(static_cast<int>(raw[i].x), static_cast<int>(raw[i].y));
    worst_lut = std::max(worst_lut, std::hypot(l.x - ref[i].x, l.y - ref[i].y));
  }
  EXPECT_LT(worst, 1e-3) << "largest difference from OpenCV over the sensor, px";
  EXPECT_LT(worst_lut, 1e-3) << "event look-up table: largest difference from OpenCV, px";
}

TEST(Camera, RadTanUndistortionMatchesOpenCvOverWholeSensor) { expectMatchesOpenCv(sliderLikeCamera()); }

TEST(Camera, EquidistantUndistortionMatchesOpenCvFisheye) { expectMatchesOpenCv(fisheyeCamera()); }

TEST(Camera, SliderDepthCalibrationFileMatchesOpenCv) {
  EDS_REQUIRE_SHARED(calib, "ecd_slider_depth/calib.txt");
  CameraModel cam = readEcdCalib(calib);
  cam.width = 240, cam.height = 180;
  EXPECT_EQ(cam.distortion, Distortion::kRadTan);
  EXPECT_NEAR(cam.k[0], -0.138592767408, 1e-15);
  expectMatchesOpenCv(cam);
}

TEST(Camera, ProjectInvertsUnproject) {
  for (const CameraModel& cam : {sliderLikeCamera(), fisheyeCamera()}) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> ux(0, cam.width - 1), uy(0, cam.height - 1), ud(0.3, 8);
    for (int i = 0; i < 1000; ++i) {
      const Vec2 px(ux(rng), uy(rng));
      const Vec3 p_c = cam.unproject(px) * ud(rng);
      EXPECT_LT((cam.project(p_c) - px).norm(), 1e-9);
    }
  }
}

TEST(Camera, DistortionMatchesOpenCvProjectPoints) {
  const CameraModel cam = sliderLikeCamera();
  const cv::Matx33d K(cam.fx, 0, cam.cx, 0, cam.fy, cam.cy, 0, 0, 1);
  const cv::Matx<double, 1, 5> D(cam.k[0], cam.k[1], cam.k[2], cam.k[3], cam.k[4]);
  std::vector<cv::Point3d> pts = {{0.1, -0.2, 1.0}, {-0.3, 0.25, 1.2}, {0.0, 0.0, 2.0}, {0.35, 0.28, 1.0}};
  std::vector<cv::Point2d> ref;
  cv::projectPoints(pts, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), K, D, ref);
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const Vec2 px = cam.project(Vec3(pts[i].x, pts[i].y, pts[i].z));
    EXPECT_NEAR(px.x(), ref[i].x, 1e-9);
    EXPECT_NEAR(px.y(), ref[i].y, 1e-9);
  }
}

TEST(Undistorter, EventLutAndImageMapAreConsistent) {
  const Undistorter und(sliderLikeCamera());
  const CameraModel& cam = und.raw();
  // Raw pixel -> LUT -> map back must land on the raw pixel again (to the map's float precision).
  double worst = 0;
  for (int y = 20; y < cam.height - 20; y += 7) {
    for (int x = 20; x < cam.width - 20; x += 7) {
      const cv::Point2f u = und.eventLut(x, y);
      const Vec3 ray = und.pinhole().unproject(Vec2(u.x, u.y));
      const Vec2 back = cam.project(ray);
      worst = std::max(worst, (back - Vec2(x, y)).norm());
    }
  }
  EXPECT_LT(worst, 1e-4);
  // An undistorted image of a distorted render of a straight edge is straight again: check that the
  // map samples the raw image where the raw camera projects the undistorted ray.
  const float mx = und.mapX().at<float>(10, 10), my = und.mapY().at<float>(10, 10);
  const Vec2 expect = cam.project(und.pinhole().unproject(Vec2(10, 10)));
  EXPECT_NEAR(mx, expect.x(), 1e-3);
  EXPECT_NEAR(my, expect.y(), 1e-3);
}

// Pincushion distortion: the undistorted grid's corners look beyond the raw image. There a chosen
// border value (0 by default, NaN for an image whose NaNs mark pixels without information); inside,
// the raw image's values.
TEST(Undistorter, BorderValueFillsWhatTheRawImageDoesNotSee) {
  CameraModel cam = sliderLikeCamera();
  cam.k = {0.3, 0, 0, 0, 0};
  const Undistorter und(cam);
  const cv::Mat raw(cam.height, cam.width, CV_32F, cv::Scalar(0.5));
  const cv::Mat zero = und.undistortImage(raw), nan = und.undistortImage(raw, std::nan(""));
  int outside = 0, inside = 0;
  for (int y = 0; y < raw.rows; ++y)
    for (int x = 0; x < raw.cols; ++x) {
      const float mx = und.mapX().at<float>(y, x), my = und.mapY().at<float>(y, x);
      if (mx < -1 || my < -1 || mx > raw.cols || my > raw.rows) {
        ++outside;
        EXPECT_EQ(zero.at<float>(y, x), 0.f);
        EXPECT_TRUE(std::isnan(nan.at<float>(y, x)));
      } else if (mx >= 1 && my >= 1 && mx <= raw.cols - 2 && my <= raw.rows - 2) {
        ++inside;
        EXPECT_FLOAT_EQ(nan.at<float>(y, x), 0.5f);
      }
    }
  EXPECT_GT(outside, 100);
  EXPECT_GT(inside, raw.rows * raw.cols / 2);
}

TEST(Camera, ValidateRejectsNaN) {
  CameraModel cam = sliderLikeCamera();
  cam.k[1] = std::nan("");
  EXPECT_THROW(cam.validate("test"), std::invalid_argument);
}

}  // namespace
}  // namespace eds
