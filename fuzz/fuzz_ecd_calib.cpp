// ECD calib.txt: fx fy cx cy k1 k2 p1 p2 [k3].
#include "fuzz_input.hpp"
#include "io/sequence.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto file = eds::fuzz::writeInput(data, size, "calib.txt");
  eds::fuzz::expectOnlyInputErrors([&] { eds::readEcdCalib(file); });
  return 0;
}
