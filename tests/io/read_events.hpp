#pragma once
// Reading a whole event stream in tests, checking the EventSource contract on the way.
#include <gtest/gtest.h>

#include <cstddef>

#include "io/event_source.hpp"

namespace eds::test {

// Every event of `src`, read `chunk` at a time; each read must append at most `chunk` events.
inline EventArray readAll(EventSource& src, std::size_t chunk) {
  EventArray all;
  while (true) {
    const std::size_t before = all.size();
    const std::size_t n = src.read(all, chunk);
    EXPECT_LE(n, chunk);
    EXPECT_EQ(all.size(), before + n);
    if (n == 0) return all;
  }
}

}  // namespace eds::test
