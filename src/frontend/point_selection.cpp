#include "frontend/point_selection.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

namespace eds {

void PointSelectionConfig::validate() const {
  if (tile < 1) throw std::invalid_argument("point selection: tile must be >= 1");
  if (!(fraction > 0 && fraction <= 1))
    throw std::invalid_argument("point selection: fraction must be in (0, 1]");
  if (border < 0 || max_points < 0 || !(full_density_pixels >= 0))
    throw std::invalid_argument("point selection: negative border, max_points or full_density_pixels");
}

std::vector<cv::Point> selectPoints(const cv::Mat& gx, const cv::Mat& gy, const PointSelectionConfig& cfg) {
  cfg.validate();
  const int W = gx.cols, H = gx.rows;
  struct Cand {
    float mag2;
    cv::Point p;
  };
  std::vector<Cand> tile_c, chosen;
  const float min2 = static_cast<float>(cfg.min_gradient * cfg.min_gradient);
  int tile = cfg.tile;
  double fraction = cfg.fraction;
  const double pixels = static_cast<double>(W) * H;
  if (cfg.full_density_pixels > 0 && pixels > cfg.full_density_pixels) {
    tile = static_cast<int>(std::lround(cfg.tile * std::sqrt(pixels / cfg.full_density_pixels)));
    fraction = std::min(1.0, cfg.fraction * cfg.tile * cfg.tile / (static_cast<double>(tile) * tile));
  }
  for (int ty = cfg.border; ty < H - cfg.border; ty += tile) {
    for (int tx = cfg.border; tx < W - cfg.border; tx += tile) {
      tile_c.clear();
      const int y1 = std::min(ty + tile, H - cfg.border), x1 = std::min(tx + tile, W - cfg.border);
      for (int y = ty; y < y1; ++y) {
        const float* rx = gx.ptr<float>(y);
        const float* ry = gy.ptr<float>(y);
        for (int x = tx; x < x1; ++x) {
          const float m2 = rx[x] * rx[x] + ry[x] * ry[x];
          if (m2 >= min2) tile_c.push_back({m2, {x, y}});
        }
      }
      const auto keep = std::min<std::size_t>(
          tile_c.size(), static_cast<std::size_t>(std::ceil(fraction * (y1 - ty) * (x1 - tx))));
      std::partial_sort(tile_c.begin(), tile_c.begin() + keep, tile_c.end(),
                        [](const Cand& a, const Cand& b) { return a.mag2 > b.mag2; });
      chosen.insert(chosen.end(), tile_c.begin(), tile_c.begin() + keep);
    }
  }
  if (cfg.max_points > 0 && chosen.size() > static_cast<std::size_t>(cfg.max_points)) {
    std::nth_element(chosen.begin(), chosen.begin() + cfg.max_points, chosen.end(),
                     [](const Cand& a, const Cand& b) { return a.mag2 > b.mag2; });
    chosen.resize(cfg.max_points);
  }
  std::vector<cv::Point> out;
  out.reserve(chosen.size());
  for (const Cand& c : chosen) out.push_back(c.p);
  std::sort(out.begin(), out.end(),
            [](const cv::Point& a, const cv::Point& b) { return a.y != b.y ? a.y < b.y : a.x < b.x; });
  return out;
}

std::vector<cv::Point> selectPointsOnIntensity(const cv::Mat& image, const PointSelectionConfig& cfg) {
  cv::Mat gx, gy;
  cv::Sobel(image, gx, CV_32F, 1, 0, 3, 1.0 / 8.0, 0, cv::BORDER_REPLICATE);
  cv::Sobel(image, gy, CV_32F, 0, 1, 3, 1.0 / 8.0, 0, cv::BORDER_REPLICATE);
  return selectPoints(gx, gy, cfg);
}

}  // namespace eds
