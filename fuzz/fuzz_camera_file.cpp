// Any calibration file `--calib` takes, recognized by content (calib.txt, Kalibr, DSEC, Basalt JSON).
#include "fuzz_input.hpp"
#include "io/sequence.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto file = eds::fuzz::writeInput(data, size, "calibration");
  eds::fuzz::expectOnlyInputErrors([&] { eds::readCameraFile(file); });
  eds::fuzz::expectOnlyInputErrors([&] { eds::readBasaltCalibration(file); });
  return 0;
}
