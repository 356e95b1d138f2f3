// Odometry configuration YAML (`eds run --config`).
#include "fuzz_input.hpp"
#include "system/odometry_config_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto file = eds::fuzz::writeInput(data, size, "config.yaml");
  eds::fuzz::expectOnlyInputErrors([&] {
    eds::OdometryConfig cfg = eds::defaultOdometryConfig(240, 180);
    eds::loadOdometryConfig(file, cfg);
  });
  return 0;
}
