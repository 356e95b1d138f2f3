// Kalibr camchain YAML and DSEC cam_to_cam YAML.
#include "fuzz_input.hpp"
#include "io/kalibr.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto file = eds::fuzz::writeInput(data, size, "camchain.yaml");
  eds::fuzz::expectOnlyInputErrors([&] { eds::readKalibrCamchain(file.string()); });
  eds::fuzz::expectOnlyInputErrors([&] { eds::readDsecCamera(file.string()); });
  return 0;
}
