#include "report/report_images.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <vector>

namespace eds::report {

namespace {

std::string base64(const std::vector<uchar>& in) {
  static constexpr char kAlphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((in.size() + 2) / 3 * 4);
  for (std::size_t i = 0; i < in.size(); i += 3) {
    const std::uint32_t n = (std::uint32_t{in[i]} << 16) |
                            (i + 1 < in.size() ? std::uint32_t{in[i + 1]} << 8 : 0) |
                            (i + 2 < in.size() ? std::uint32_t{in[i + 2]} : 0);
    out += kAlphabet[(n >> 18) & 63];
    out += kAlphabet[(n >> 12) & 63];
    out += i + 1 < in.size() ? kAlphabet[(n >> 6) & 63] : '=';
    out += i + 2 < in.size() ? kAlphabet[n & 63] : '=';
  }
  return out;
}

// Quantile q of the values (0 for none).
double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  const auto k = static_cast<std::ptrdiff_t>(q * static_cast<double>(v.size() - 1) + 0.5);
  std::nth_element(v.begin(), v.begin() + k, v.end());
  return v[static_cast<std::size_t>(k)];
}

// Turbo colours of the keyframe's inverse depths (near red, far blue).
std::vector<cv::Vec3b> depthColours(const Keyframe& kf) {
  std::vector<double> inv;
  for (const KeyframePoint& p : kf.points) inv.push_back(p.inv_depth);
  const double lo = quantile(inv, 0.05), hi = quantile(inv, 0.95);
  cv::Mat level(1, static_cast<int>(inv.size()), CV_8U);
  for (std::size_t i = 0; i < inv.size(); ++i)
    level.at<uchar>(0, static_cast<int>(i)) =
        cv::saturate_cast<uchar>(hi > lo ? 255.0 * (inv[i] - lo) / (hi - lo) : 128.0);
  std::vector<cv::Vec3b> out;
  if (inv.empty()) return out;
  cv::Mat colour;
  cv::applyColorMap(level, colour, cv::COLORMAP_TURBO);
  for (int i = 0; i < colour.cols; ++i) out.push_back(colour.at<cv::Vec3b>(0, i));
  return out;
}

cv::Mat drawPoints(const Keyframe& kf, cv::Mat canvas_bgr, int scale) {
  const std::vector<cv::Vec3b> colours = depthColours(kf);
  for (std::size_t i = 0; i < kf.points.size(); ++i) {
    const cv::Point c(static_cast<int>(std::lround((kf.points[i].u + 0.5) * scale - 0.5)),
                      static_cast<int>(std::lround((kf.points[i].v + 0.5) * scale - 0.5)));
    cv::circle(canvas_bgr, c, std::max(2, scale), cv::Scalar(colours[i]), cv::FILLED, cv::LINE_AA);
  }
  return canvas_bgr;
}

}  // namespace

std::string pngDataUri(const cv::Mat& image) {
  std::vector<uchar> png;
  if (!cv::imencode(".png", image, png)) throw std::runtime_error("PNG encoding failed");
  return "data:image/png;base64," + base64(png);
}

std::string jpegDataUri(const cv::Mat& image) {
  std::vector<uchar> jpg;
  if (!cv::imencode(".jpg", image, jpg, {cv::IMWRITE_JPEG_QUALITY, 90}))
    throw std::runtime_error("JPEG encoding failed");
  return "data:image/jpeg;base64," + base64(jpg);
}

int displayScale(int width, int min_width) {
  return width <= 0 ? 1 : std::max(1, (min_width + width - 1) / width);
}

cv::Mat keyframePointsImage(const Keyframe& kf) {
  const int s = displayScale(kf.image.cols);
  cv::Mat gray8, big, bgr;
  kf.image.convertTo(gray8, CV_8U, kf.image.depth() == CV_8U ? 1.0 : 255.0);
  cv::resize(gray8, big, cv::Size(), s, s, cv::INTER_NEAREST);
  cv::cvtColor(big, bgr, cv::COLOR_GRAY2BGR);
  return drawPoints(kf, bgr, s);
}

cv::Mat keyframeDepthImage(const Keyframe& kf) {
  const int s = displayScale(kf.image.cols);
  return drawPoints(kf, cv::Mat(kf.image.rows * s, kf.image.cols * s, CV_8UC3, cv::Scalar(20, 20, 20)), s);
}

cv::Mat signedImage(const cv::Mat& x) {
  std::vector<double> mag;
  for (int r = 0; r < x.rows; ++r)
    for (int c = 0; c < x.cols; ++c)
      if (const float v = x.at<float>(r, c); v != 0 && std::isfinite(v)) mag.push_back(std::abs(v));
  const double top = std::max(quantile(mag, 0.99), 1e-12);
  cv::Mat out(x.rows, x.cols, CV_8UC3);
  for (int r = 0; r < x.rows; ++r)
    for (int c = 0; c < x.cols; ++c) {
      const float v = x.at<float>(r, c);
      const double a = std::isfinite(v) ? std::clamp(std::abs(v) / top, 0.0, 1.0) : 0.0;
      const auto fade = cv::saturate_cast<uchar>(255.0 * (1.0 - a));
      out.at<cv::Vec3b>(r, c) = v > 0 ? cv::Vec3b(fade, fade, 255) : cv::Vec3b(255, fade, fade);  // BGR
    }
  return out;
}

}  // namespace eds::report
