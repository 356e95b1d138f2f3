// libcaer EventPacket payloads, plain (first byte odd) and compressed: any bytes decode or are refused
// with a PayloadError, never a crash.
#include <cstddef>
#include <cstdint>

#include "io/libcaer_payload.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  eds::EventArray out;
  try {
    if (data[0] & 1)
      eds::decodeLibcaer(data + 1, size - 1, 1'700'000'000'000'000'000, out);
    else
      eds::decodeLibcaerCompressed(data + 1, size - 1, 1'700'000'000'000'000'000, out);
  } catch (const eds::PayloadError&) {
  }
  return 0;
}
