// TUM trajectories (ground truth, `eds eval --est`), sorted and unsorted.
#include "fuzz_input.hpp"
#include "io/trajectory_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto file = eds::fuzz::writeInput(data, size, "trajectory.txt");
  eds::fuzz::expectOnlyInputErrors([&] { eds::readTum(file); });
  eds::fuzz::expectOnlyInputErrors([&] { eds::readTum(file, true); });
  return 0;
}
