#include "io/ros_recording.hpp"

#include <cstring>
#include <opencv2/imgproc.hpp>

namespace eds {

namespace {

// The name of the chosen topic of one of `types`; empty when the bag has none.
std::string chooseTopicName(const RosBagReader& bag, const std::vector<std::string>& types,
                            const std::string& wanted, const std::string& kind, const char* option) {
  const auto topic = chooseTopic(bag, types, wanted, kind, option);
  return topic ? bag.topics()[*topic].name : std::string();
}

// The only CameraInfo topic, or with several cameras the one beside the chosen image topic
// (".../image_raw" -> ".../camera_info"); empty otherwise, so a calibration must come from elsewhere.
std::string cameraInfoTopic(const RosBagReader& bag, const std::string& image_topic) {
  std::vector<std::string> found;
  for (const RosTopic& t : bag.topics())
    if (t.type == "sensor_msgs/CameraInfo") found.push_back(t.name);
  if (found.size() == 1) return found[0];
  const std::size_t slash = image_topic.rfind('/');
  const std::string beside = image_topic.substr(0, slash == std::string::npos ? 0 : slash) + "/camera_info";
  return std::find(found.begin(), found.end(), beside) != found.end() ? beside : std::string();
}

StampedPose decodePose(RosMessageReader& r, bool transform) {
  StampedPose p;
  p.t = r.header();
  if (transform) r.string("child_frame_id");
  double v[7];
  for (double& d : v) d = r.f64("pose");
  const Quat q(v[6], v[3], v[4], v[5]);
  if (!(q.norm() > 0.99 && q.norm() < 1.01)) throw r.error("pose quaternion is not unit");
  p.T_w_c = SE3(q, Vec3(v[0], v[1], v[2]));  // as readTum builds it
  return p;
}

// sensor_msgs/Imu: header, orientation (4) + covariance (9), angular_velocity (3) + covariance (9),
// linear_acceleration (3) + covariance (9), all float64.
ImuSample decodeImu(RosMessageReader& r) {
  ImuSample s;
  s.t = r.header();
  for (int i = 0; i < 13; ++i) r.f64("orientation");
  for (double& w : s.gyro) w = r.f64("angular_velocity");
  for (int i = 0; i < 9; ++i) r.f64("angular_velocity_covariance");
  for (double& a : s.acc) a = r.f64("linear_acceleration");
  return s;
}

}  // namespace

cv::Mat decodeRosImage(RosMessageReader& r) {
  r.header();
  const std::uint32_t height = r.u32("height"), width = r.u32("width");
  const std::string encoding = r.string("encoding");
  const bool big_endian = r.u8("is_bigendian") != 0;
  const std::uint32_t step = r.u32("step");
  const ByteView data = r.bytes("data");
  struct Enc {
    const char* name;
    int type, code;
  };
  static const Enc kEncodings[] = {{"mono8", CV_8UC1, -1},
                                   {"8UC1", CV_8UC1, -1},
                                   {"mono16", CV_16UC1, -1},
                                   {"16UC1", CV_16UC1, -1},
                                   {"rgb8", CV_8UC3, cv::COLOR_RGB2GRAY},
                                   {"bgr8", CV_8UC3, cv::COLOR_BGR2GRAY},
                                   {"rgba8", CV_8UC4, cv::COLOR_RGBA2GRAY},
                                   {"bgra8", CV_8UC4, cv::COLOR_BGRA2GRAY}};
  const Enc* enc = nullptr;
  for (const Enc& e : kEncodings)
    if (encoding == e.name) enc = &e;
  if (!enc)
    throw r.error("image encoding '" + encoding +
                  "' is not read (mono8, mono16, rgb8, bgr8, rgba8, bgra8 are)");
  constexpr std::uint32_t kMaxSide = 1 << 16;
  if (width > kMaxSide || height > kMaxSide)
    throw r.error("image of " + std::to_string(width) + "x" + std::to_string(height) +
                  " pixels: no camera has that many");
  const std::size_t row = static_cast<std::size_t>(width) * CV_ELEM_SIZE(enc->type);
  if (width == 0 || height == 0 || step < row || data.size() < static_cast<std::size_t>(step) * height)
    throw r.error("image of " + std::to_string(data.size()) + " bytes does not hold " +
                  std::to_string(width) + "x" + std::to_string(height) + " " + encoding + " with step " +
                  std::to_string(step));
  // Row by row into an image of its own: a message's step need not be a multiple of the pixel size
  // (OpenCV refuses such a view) and its data need not be aligned for 16-bit pixels.
  cv::Mat v(static_cast<int>(height), static_cast<int>(width), enc->type);
  for (std::uint32_t y = 0; y < height; ++y)
    std::memcpy(v.ptr(static_cast<int>(y)), data.data() + static_cast<std::size_t>(y) * step, row);
  cv::Mat gray;
  if (enc->type == CV_16UC1) {
    if (big_endian)
      v.forEach<std::uint16_t>(
          [](std::uint16_t& p, const int*) { p = static_cast<std::uint16_t>(p << 8 | p >> 8); });
    v.convertTo(gray, CV_8U, 1.0 / 256.0);
  } else if (enc->code >= 0) {
    cv::cvtColor(v, gray, enc->code);
  } else {
    gray = v;
  }
  return gray;
}

CameraModel decodeCameraInfo(RosMessageReader& r) {
  r.header();
  CameraModel cam;
  cam.height = static_cast<int>(r.u32("height"));
  cam.width = static_cast<int>(r.u32("width"));
  const std::string model = r.string("distortion_model");
  const std::uint32_t nd = r.sequenceLength(8, "D");
  std::vector<double> d(nd);
  for (double& x : d) x = r.f64("D");
  double K[9];
  for (double& x : K) x = r.f64("K");
  cam.fx = K[0], cam.fy = K[4], cam.cx = K[2], cam.cy = K[5];
  const bool all_zero = std::all_of(d.begin(), d.end(), [](double x) { return x == 0.0; });
  if (model == "plumb_bob" || model == "rational_polynomial") {
    if (model == "rational_polynomial" && std::any_of(d.begin() + std::min<std::size_t>(5, d.size()), d.end(),
                                                      [](double x) { return x != 0.0; }))
      throw r.error("rational_polynomial distortion with k4..k6 is not supported");
    cam.distortion = all_zero ? Distortion::kNone : Distortion::kRadTan;
  } else if (model == "equidistant") {
    cam.distortion = all_zero ? Distortion::kNone : Distortion::kEquidistant;
  } else if (!(model.empty() && all_zero)) {
    throw r.error("distortion model '" + model + "' is not supported (plumb_bob, equidistant are)");
  }
  for (std::size_t i = 0; i < std::min<std::size_t>(d.size(), 5); ++i) cam.k[i] = d[i];
  try {
    cam.validate("CameraInfo");
  } catch (const std::invalid_argument& e) {
    throw r.error(e.what());
  }
  return cam;
}

RosRecordingIndex indexRosRecording(const std::filesystem::path& path, const RosTopicChoice& choice) {
  auto bag = openRosBag(path);
  RosRecordingIndex idx;
  idx.image_topic = chooseTopicName(*bag, {"sensor_msgs/Image"}, choice.image, "image", "--image-topic");
  idx.gt_topic = chooseTopicName(*bag, {"geometry_msgs/PoseStamped", "geometry_msgs/TransformStamped"},
                                 choice.ground_truth, "ground-truth pose", "--gt-topic");
  idx.camera_info_topic = cameraInfoTopic(*bag, idx.image_topic);
  RosMessage m;
  while (bag->next(m)) {
    const RosTopic& t = bag->topics()[m.topic];
    if (t.type == "sensor_msgs/Imu") {
      if (idx.imu_topic.empty()) idx.imu_topic = t.name;
      if (t.name != idx.imu_topic) continue;
      RosMessageReader r(m.data, t.serialization);
      idx.imu_samples.push_back(decodeImu(r));
      continue;
    }
    const bool image = t.name == idx.image_topic, gt = t.name == idx.gt_topic;
    const bool info = t.name == idx.camera_info_topic && !idx.camera;
    if (!image && !gt && !info) continue;
    RosMessageReader r(m.data, t.serialization);
    try {
      if (image) {
        const TimeNs stamp = r.header();
        if (!idx.frames.empty() && stamp <= idx.frames.back().t) throw r.error("image stamps must increase");
        idx.frames.push_back({stamp, m.index});
      } else if (gt) {
        idx.ground_truth.push_back(decodePose(r, t.type == "geometry_msgs/TransformStamped"));
      } else {
        idx.camera = decodeCameraInfo(r);
      }
    } catch (const InputError& e) {
      throw InputError(bag->path(), "message " + std::to_string(m.index) + " on " + t.name + ": " + e.what());
    }
  }
  return idx;
}

cv::Mat RosFrameLoader::load(std::uint64_t message) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!bag_) bag_ = openRosBag(path_);
  if (message < next_index_) {
    bag_->rewind();
    next_index_ = 0;
  }
  RosMessage m;
  while (bag_->next(m)) {
    next_index_ = m.index + 1;
    if (m.index != message) continue;
    RosMessageReader r(m.data, bag_->topics()[m.topic].serialization);
    try {
      return decodeRosImage(r);
    } catch (const InputError& e) {
      throw InputError(bag_->path(), "message " + std::to_string(m.index) + ": " + e.what());
    }
  }
  throw InputError(path_.string(), "message " + std::to_string(message) + " not found (the bag changed?)");
}

}  // namespace eds
