#pragma once
// Decompressing the blocks of recording containers (bag chunks, MCAP chunks, AEDAT packets) with the
// Debian liblz4 and libzstd; errors name the file and the offset of the compressed block.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "io/binary_file.hpp"

namespace eds {

// Into `out`, whose size is the decompressed size the container's record gives.
void lz4FrameDecompress(const std::uint8_t* in, std::size_t in_size, std::vector<std::uint8_t>& out,
                        const std::string& file, std::uint64_t offset);
// The same for blocks whose decompressed size is not known beforehand (at most 1 GiB).
void lz4FrameDecompressAll(const std::uint8_t* in, std::size_t in_size, std::vector<std::uint8_t>& out,
                           const std::string& file, std::uint64_t offset);
void zstdDecompressAll(const std::uint8_t* in, std::size_t in_size, std::vector<std::uint8_t>& out,
                       const std::string& file, std::uint64_t offset);
void zstdDecompress(const std::uint8_t* in, std::size_t in_size, std::vector<std::uint8_t>& out,
                    const std::string& file, std::uint64_t offset);

}  // namespace eds
