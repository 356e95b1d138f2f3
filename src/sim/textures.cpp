#include "sim/textures.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <opencv2/imgproc.hpp>
#include <random>
#include <stdexcept>
#include <vector>

// Feature sizes are in texels (not fractions of the image), so a texture looks the same whatever its
// size and a preset controls the metric scale of the detail through the plane's texel size alone.

namespace eds::sim {

namespace {

// Uniform doubles from the raw 64-bit output: std::uniform_real_distribution differs between standard
// libraries, and the same seed must give the same bytes everywhere.
class Rng {
 public:
  explicit Rng(std::uint64_t seed) : gen_(seed) {}
  double uniform(double a = 0.0, double b = 1.0) {
    return a + (b - a) * static_cast<double>(gen_() >> 11) * 0x1.0p-53;
  }
  int integer(int a, int b) { return a + static_cast<int>(uniform() * (b - a + 1)) % (b - a + 1); }

 private:
  std::mt19937_64 gen_;
};

// Independent sub-seeds for the parts of a composite texture.
std::uint64_t subSeed(std::uint64_t seed, std::uint64_t tag) {
  std::uint64_t z = seed + 0x9e3779b97f4a7c15ULL * (tag + 1);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

// Maps the 1st..99th percentile of a CV_32F image onto 0..255 (CV_8U): high contrast whatever the
// raw range, without a few outliers squeezing everything else.
cv::Mat stretchTo8u(const cv::Mat& f) {
  double lo, hi;
  cv::minMaxLoc(f, &lo, &hi);
  if (hi - lo < 1e-12) return cv::Mat(f.size(), CV_8U, cv::Scalar(128));
  constexpr int kBins = 4096;
  std::vector<int> hist(kBins, 0);
  const double scale = (kBins - 1) / (hi - lo);
  for (int r = 0; r < f.rows; ++r) {
    const float* p = f.ptr<float>(r);
    for (int c = 0; c < f.cols; ++c) ++hist[static_cast<int>((p[c] - lo) * scale)];
  }
  const double n = static_cast<double>(f.total());
  auto quantile = [&](double q) {
    double acc = 0;
    for (int b = 0; b < kBins; ++b) {
      acc += hist[b];
      if (acc >= q * n) return lo + b / scale;
    }
    return hi;
  };
  const double q0 = quantile(0.01), q1 = std::max(quantile(0.99), q0 + 1e-9);
  cv::Mat out;
  f.convertTo(out, CV_8U, 255.0 / (q1 - q0), -255.0 * q0 / (q1 - q0));  // saturating
  return out;
}

// Zero mean, unit standard deviation (in place).
void standardize(cv::Mat& f) {
  cv::Scalar mean, sd;
  cv::meanStdDev(f, mean, sd);
  f = (f - mean[0]) / std::max(sd[0], 1e-12);
}

// Sum of octaves of value noise (random grids upsampled bicubically) with cell sizes from `min_cell`
// to `max_cell` texels, amplitude ~ cell^exponent. With `edge_gain` > 0 each octave is first pushed
// towards +-1 (a clamped ramp), so that every scale contributes edges, not just soft shading, as
// natural images do. Standardized.
cv::Mat valueNoise(int w, int h, std::uint64_t seed, double min_cell, double max_cell, double exponent = 0.8,
                   float edge_gain = 0.0f) {
  Rng rng(seed);
  cv::Mat sum(h, w, CV_32F, cv::Scalar(0)), up;
  for (double cell = max_cell; cell >= min_cell * 0.999; cell /= 2.0) {
    const int gw = std::max(2, static_cast<int>(std::lround(w / cell)) + 1);
    const int gh = std::max(2, static_cast<int>(std::lround(h / cell)) + 1);
    cv::Mat grid(gh, gw, CV_32F);
    for (int r = 0; r < gh; ++r)
      for (int c = 0; c < gw; ++c) grid.at<float>(r, c) = static_cast<float>(rng.uniform(-1.0, 1.0));
    cv::resize(grid, up, cv::Size(w, h), 0, 0, cv::INTER_CUBIC);
    const auto amp = static_cast<float>(std::pow(cell, exponent));
    for (int r = 0; r < h; ++r) {
      const float* u = up.ptr<float>(r);
      float* o = sum.ptr<float>(r);
      if (edge_gain > 0)
        for (int c = 0; c < w; ++c) o[c] += amp * std::clamp(edge_gain * u[c], -1.0f, 1.0f);
      else
        for (int c = 0; c < w; ++c) o[c] += amp * u[c];
    }
  }
  standardize(sum);
  return sum;
}

// Soft-clipped contrast x / (1 + |x|): smooth noise becomes regions with sharp-ish edges (cheaper
// than tanh, same effect).
cv::Mat sharpen(const cv::Mat& z, float gain) {
  cv::Mat out(z.size(), CV_32F);
  for (int r = 0; r < z.rows; ++r) {
    const float* p = z.ptr<float>(r);
    float* o = out.ptr<float>(r);
    for (int c = 0; c < z.cols; ++c) {
      const float x = gain * p[c];
      o[c] = x / (1.0f + std::abs(x));
    }
  }
  return out;
}

cv::Mat noiseTexture(int w, int h, std::uint64_t seed) {
  const double max_cell = std::max(4.0, std::min(128.0, std::max(w, h) / 2.0));
  return stretchTo8u(sharpen(valueNoise(w, h, seed, 2.0, max_cell, 0.25, 3.0f), 1.0f));
}

cv::Mat checkerTexture(int w, int h, std::uint64_t seed) {
  Rng rng(seed);
  const int cell = rng.integer(8, 16);
  const int ox = rng.integer(0, cell - 1), oy = rng.integer(0, cell - 1);
  // Each square has its own gray (dark or light), so the pattern is not periodic: a tracker cannot
  // lock onto the wrong square.
  const int nx = (w + ox) / cell + 1, ny = (h + oy) / cell + 1;
  std::vector<std::uint8_t> gray(static_cast<std::size_t>(nx) * ny);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i)
      gray[static_cast<std::size_t>(j) * nx + i] =
          static_cast<std::uint8_t>((i + j) % 2 ? rng.uniform(185, 245) : rng.uniform(10, 70));
  cv::Mat out(h, w, CV_8U);
  for (int r = 0; r < h; ++r) {
    auto* o = out.ptr<std::uint8_t>(r);
    const std::size_t row = static_cast<std::size_t>((r + oy) / cell) * nx;
    for (int c = 0; c < w; ++c) o[c] = gray[row + (c + ox) / cell];
  }
  return out;
}

cv::Mat bricksTexture(int w, int h, std::uint64_t seed) {
  Rng rng(seed);
  const int bh = rng.integer(10, 14);  // course height, texels
  const int bw = static_cast<int>(std::lround(bh * rng.uniform(2.0, 2.6)));
  const int mortar = 2;
  const float mortar_gray = static_cast<float>(rng.uniform(200, 230));
  // Grain inside the bricks, so their faces are not flat.
  cv::Mat grain = valueNoise(w, h, subSeed(seed, 1), 2.0, 8.0);
  cv::Mat out(h, w, CV_32F);
  const int rows = h / bh + 2;
  for (int course = 0; course < rows; ++course) {
    const int shift = (course % 2) * (bw / 2) + rng.integer(0, 3);
    const int y0 = course * bh;
    const int cols = (w + shift) / bw + 2;
    std::vector<float> gray(cols);
    for (float& g : gray) g = static_cast<float>(rng.uniform(35, 150));
    for (int r = y0; r < std::min(h, y0 + bh); ++r) {
      float* o = out.ptr<float>(r);
      const float* gr = grain.ptr<float>(r);
      for (int c = 0; c < w; ++c) {
        const int xb = c + shift;
        const bool in_mortar = (r - y0) < mortar || (xb % bw) < mortar;
        o[c] = in_mortar ? mortar_gray + 6.0f * gr[c] : gray[xb / bw] + 12.0f * gr[c];
      }
    }
  }
  cv::Mat u8;
  out.convertTo(u8, CV_8U);
  return u8;
}

cv::Mat blobsTexture(int w, int h, std::uint64_t seed) {
  Rng rng(seed);
  cv::Mat out(h, w, CV_8U, cv::Scalar(rng.uniform(60, 200)));
  // Equal coverage per octave of radius, largest first so that small blobs stay visible on top.
  const double max_r = std::max(6.0, std::max(w, h) / 8.0);
  for (double s = max_r / 2.0; s >= 2.0; s /= 2.0) {
    const int count = static_cast<int>(std::ceil(0.45 * w * h / (std::numbers::pi * 2.25 * s * s)));
    for (int i = 0; i < count; ++i) {
      const cv::Point2d centre(rng.uniform(-s, w + s), rng.uniform(-s, h + s));
      const double a = rng.uniform(s, 2 * s), b = a * rng.uniform(0.4, 1.0);
      const double angle = rng.uniform(0, 180);
      const double gray = rng.uniform() < 0.5 ? rng.uniform(0, 90) : rng.uniform(165, 255);
      // Sub-pixel coordinates (shift 4) for smooth outlines.
      constexpr int kShift = 4;
      constexpr double kScale = 1 << kShift;
      cv::ellipse(out, cv::Point(cvRound(centre.x * kScale), cvRound(centre.y * kScale)),
                  cv::Size(cvRound(a * kScale), cvRound(b * kScale)), angle, 0, 360, cv::Scalar(gray),
                  cv::FILLED, cv::LINE_AA, kShift);
    }
  }
  return out;
}

cv::Mat stripesTexture(int w, int h, std::uint64_t seed) {
  Rng rng(seed);
  const double angle = rng.uniform(0, std::numbers::pi);
  const double ca = std::cos(angle), sa = std::sin(angle);
  // Band boundaries along the stripe normal at a quarter texel; alternately dark and light bands of
  // random widths (2-24 texels), so the pattern has several scales and no single period.
  constexpr int kSub = 4;
  const double extent = std::abs(ca) * w + std::abs(sa) * h + 2;
  const double origin = std::min(0.0, ca * w) + std::min(0.0, sa * h) - 1;
  std::vector<std::uint8_t> lut(static_cast<std::size_t>(extent * kSub) + 2);
  std::size_t pos = 0;
  bool dark = rng.uniform() < 0.5;
  while (pos < lut.size()) {
    const std::size_t width = static_cast<std::size_t>(rng.uniform(2, 24) * kSub);
    const auto gray = static_cast<std::uint8_t>(dark ? rng.uniform(0, 90) : rng.uniform(165, 255));
    for (std::size_t i = pos; i < std::min(lut.size(), pos + width); ++i) lut[i] = gray;
    pos += width;
    dark = !dark;
  }
  cv::Mat out(h, w, CV_8U);
  for (int r = 0; r < h; ++r) {
    auto* o = out.ptr<std::uint8_t>(r);
    for (int c = 0; c < w; ++c) o[c] = lut[static_cast<std::size_t>((ca * c + sa * r - origin) * kSub)];
  }
  return out;
}

// A soft region mask in [0, 1] from coarse noise, made at 1/16 resolution (it is smooth) and
// upsampled: the full-resolution octaves would cost more than the rest of the texture.
cv::Mat regionMask(int w, int h, std::uint64_t seed, double threshold) {
  constexpr int kDown = 16;
  const int sw = std::max(2, w / kDown), sh = std::max(2, h / kDown);
  // Regions of ~30-150 texels: a camera sees several of them on one plane.
  cv::Mat z = valueNoise(sw, sh, seed, 2.0, std::max(2.0, std::min(8.0, std::max(sw, sh) / 2.0)));
  cv::Mat m = sharpen(z - threshold, 4.0f), up;
  m = 0.5 * (m + 1.0);
  cv::resize(m, up, cv::Size(w, h), 0, 0, cv::INTER_LINEAR);
  return up;
}

cv::Mat mixTexture(int w, int h, std::uint64_t seed) {
  cv::Mat noise, blobs, stripes, checker;
  noiseTexture(w, h, subSeed(seed, 10)).convertTo(noise, CV_32F);
  blobsTexture(w, h, subSeed(seed, 11)).convertTo(blobs, CV_32F);
  stripesTexture(w, h, subSeed(seed, 12)).convertTo(stripes, CV_32F);
  checkerTexture(w, h, subSeed(seed, 13)).convertTo(checker, CV_32F);
  const cv::Mat m1 = regionMask(w, h, subSeed(seed, 20), 0.0);
  const cv::Mat m2 = regionMask(w, h, subSeed(seed, 21), 1.1);  // ~15% stripes
  const cv::Mat m3 = regionMask(w, h, subSeed(seed, 22), 1.1);  // ~15% checker
  cv::Mat out = noise.mul(m1) + blobs.mul(1.0 - m1);
  out = stripes.mul(m2) + out.mul(1.0 - m2);
  out = checker.mul(m3) + out.mul(1.0 - m3);
  return stretchTo8u(out);
}

}  // namespace

const char* proceduralNames() { return "noise, checker, bricks, blobs, stripes, mix"; }

cv::Mat proceduralTexture(const std::string& name, int width, int height, std::uint64_t seed) {
  if (width <= 0 || height <= 0)
    throw std::invalid_argument("procedural texture size must be positive, got " + std::to_string(width) +
                                "x" + std::to_string(height));
  if (name == "noise") return noiseTexture(width, height, seed);
  if (name == "checker") return checkerTexture(width, height, seed);
  if (name == "bricks") return bricksTexture(width, height, seed);
  if (name == "blobs") return blobsTexture(width, height, seed);
  if (name == "stripes") return stripesTexture(width, height, seed);
  if (name == "mix") return mixTexture(width, height, seed);
  throw std::invalid_argument("unknown procedural texture '" + name + "' (known: " + proceduralNames() + ")");
}

std::optional<ProceduralSource> parseProceduralSource(const std::string& source) {
  static constexpr std::string_view kPrefix = "procedural:";
  if (source.rfind(kPrefix, 0) != 0) return std::nullopt;
  ProceduralSource p;
  const std::string rest = source.substr(kPrefix.size());
  const auto colon = rest.find(':');
  p.name = rest.substr(0, colon);
  if (colon != std::string::npos) {
    const std::string seed = rest.substr(colon + 1);
    std::size_t used = 0;
    try {
      p.seed = std::stoull(seed, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (seed.empty() || used != seed.size() || seed[0] == '-')
      throw std::invalid_argument("bad seed '" + seed + "' in texture source '" + source + "'");
  }
  static constexpr std::array<std::string_view, 6> kNames = {"noise", "checker", "bricks",
                                                             "blobs", "stripes", "mix"};
  if (std::find(kNames.begin(), kNames.end(), p.name) == kNames.end())
    throw std::invalid_argument("unknown procedural texture '" + p.name + "' (known: " + proceduralNames() +
                                ")");
  return p;
}

}  // namespace eds::sim
