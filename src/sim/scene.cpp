#include "sim/scene.hpp"

#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "core/error.hpp"
#include "sim/textures.hpp"

namespace eds::sim {

namespace {

// The 8-bit texture of one spec at its final texel resolution (before blur and intensity mapping).
cv::Mat loadTexels(const TextureSpec& spec, const std::filesystem::path& base) {
  std::optional<ProceduralSource> proc;
  try {
    proc = parseProceduralSource(spec.source);
  } catch (const std::invalid_argument& e) {
    throw InputError(spec.source, e.what());
  }
  if (proc) {
    // Generated directly at the asked size: resizing would only blur it.
    int w = spec.width > 0 ? spec.width : spec.height;
    int h = spec.height > 0 ? spec.height : spec.width;
    if (w <= 0) w = h = kDefaultProceduralSize;
    return proceduralTexture(proc->name, w, h, proc->seed);
  }
  const std::filesystem::path file = base.empty() ? std::filesystem::path(spec.source) : base / spec.source;
  // Checked first: imread only logs a warning and returns nothing, for a missing file.
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec)) throw InputError(file.string(), "texture image not found");
  cv::Mat img = cv::imread(file.string(), cv::IMREAD_GRAYSCALE);
  if (img.empty()) throw InputError(file.string(), "cannot read texture image (not an image?)");
  if (spec.width > 0 || spec.height > 0) {
    // One size given: keep the aspect ratio.
    const double aspect = static_cast<double>(img.cols) / img.rows;
    const int w =
        spec.width > 0 ? spec.width : std::max(1, static_cast<int>(std::lround(spec.height * aspect)));
    const int h =
        spec.height > 0 ? spec.height : std::max(1, static_cast<int>(std::lround(spec.width / aspect)));
    if (w != img.cols || h != img.rows) {
      cv::Mat resized;
      cv::resize(img, resized, cv::Size(w, h), 0, 0, cv::INTER_AREA);
      img = resized;
    }
  }
  return img;
}

}  // namespace

void Scene::loadTextures(const std::filesystem::path& base) {
  textures.clear();
  textures.reserve(texture_specs.size());
  for (const TextureSpec& spec : texture_specs) {
    const cv::Mat texels = loadTexels(spec, base);
    // Blurred in float so that rounding adds no steps (the intensity mapping is affine, so blurring
    // before or after it is the same).
    cv::Mat f;
    texels.convertTo(f, CV_32F);
    if (spec.blur_sigma > 0)
      cv::GaussianBlur(f, f, cv::Size(0, 0), spec.blur_sigma, spec.blur_sigma, cv::BORDER_REFLECT_101);
    cv::Mat intensity;
    f.convertTo(intensity, CV_32F, spec.gain / 255.0, spec.offset);
    textures.push_back(intensity);
  }
}

}  // namespace eds::sim
