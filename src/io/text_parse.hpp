#pragma once
// Hand-written number parsing for the hot text readers. strtod and friends are locale-aware and
// 5-10x slower than needed for ~20 M events/s, and decimal seconds must become int64 nanoseconds
// exactly, which a double detour would not guarantee.
#include <cstdint>
#include <cstring>

#include "core/time.hpp"

namespace eds::text {

inline bool isSpace(char c) { return c == ' ' || c == '\t' || c == '\r' || c == ','; }
inline bool isDigit(char c) { return static_cast<unsigned char>(c - '0') < 10; }

inline const char* skipSpaces(const char* p, const char* end) {
  while (p < end && isSpace(*p)) ++p;
  return p;
}

// Parses decimal seconds ("12.345678901", "5", "5.") into nanoseconds. Digits beyond the 9th decimal
// are truncated. Returns nullptr if there is no number, a sign, exponent or overflow.
inline const char* parseSecondsNs(const char* p, const char* end, TimeNs& out) {
  const char* start = p;
  std::int64_t sec = 0;
  while (p < end && isDigit(*p)) {
    sec = sec * 10 + (*p - '0');
    if (sec > 9'000'000'000LL) return nullptr;  // beyond int64 nanoseconds
    ++p;
  }
  bool any = p != start;
  std::int64_t frac = 0;
  int ndec = 0;
  if (p < end && *p == '.') {
    ++p;
    const char* fstart = p;
    while (p < end && isDigit(*p)) {
      if (ndec < 9) {
        frac = frac * 10 + (*p - '0');
        ++ndec;
      }
      ++p;
    }
    any = any || p != fstart;
  }
  if (!any) return nullptr;
  if (p < end && (*p == 'e' || *p == 'E')) return nullptr;
  static constexpr std::int64_t kPow10[10] = {1,      10,      100,      1000,      10000,
                                              100000, 1000000, 10000000, 100000000, 1000000000};
  out = sec * kNsPerSec + frac * kPow10[9 - ndec];
  return p;
}

// Parses an unsigned integer that fits in 31 bits. Returns nullptr if no digits or too large.
inline const char* parseUint(const char* p, const char* end, std::int32_t& out) {
  const char* start = p;
  std::int64_t v = 0;
  while (p < end && isDigit(*p)) {
    v = v * 10 + (*p - '0');
    if (v > 0x7fffffff) return nullptr;
    ++p;
  }
  if (p == start) return nullptr;
  out = static_cast<std::int32_t>(v);
  return p;
}

// Eight ASCII digits in a little-endian word: validity test and value, with a handful of integer
// operations instead of eight dependent multiply-adds (the "SWAR" technique).
inline bool allDigits8(std::uint64_t v) {
  return ((v & 0xF0F0F0F0F0F0F0F0ULL) | (((v + 0x0606060606060606ULL) & 0xF0F0F0F0F0F0F0F0ULL) >> 4)) ==
         0x3333333333333333ULL;
}
inline std::uint32_t parse8Digits(std::uint64_t v) {
  v -= 0x3030303030303030ULL;
  v = v * 10 + (v >> 8);  // adjacent digit pairs
  v = (((v & 0x000000FF000000FFULL) * (100 + (1000000ULL << 32))) +
       (((v >> 16) & 0x000000FF000000FFULL) * (1 + (10000ULL << 32)))) >>
      32;
  return static_cast<std::uint32_t>(v);
}

// The canonical ECD event line "S.FFFFFFFFF X Y P\n" (or "\r\n"), single spaces, 9 decimals. Returns the
// start of the next line, or nullptr if the line is not exactly in that form: the general parser then
// handles it, including its errors. Reads at most 40 bytes from p.
inline const char* parseEcdLineFast(const char* p, TimeNs& t, std::int32_t& x, std::int32_t& y,
                                    std::int8_t& pol) {
  std::int64_t sec = 0;
  int nd = 0;
  while (isDigit(*p)) {
    sec = sec * 10 + (*p++ - '0');
    if (++nd > 10) return nullptr;
  }
  // Beyond int64 ns (year 2262): left to the careful parser, which names the problem.
  if (nd == 0 || *p != '.' || sec > INT64_MAX / kNsPerSec - 1) return nullptr;
  ++p;
  std::uint64_t w;
  std::memcpy(&w, p, 8);
  if (!allDigits8(w) || !isDigit(p[8]) || p[9] != ' ') return nullptr;
  const std::int64_t frac = static_cast<std::int64_t>(parse8Digits(w)) * 10 + (p[8] - '0');
  p += 10;
  std::int32_t v = 0;
  for (nd = 0; isDigit(*p) && nd <= 5; ++nd) v = v * 10 + (*p++ - '0');
  if (nd == 0 || nd > 5 || *p != ' ') return nullptr;
  x = v;
  ++p;
  v = 0;
  for (nd = 0; isDigit(*p) && nd <= 5; ++nd) v = v * 10 + (*p++ - '0');
  if (nd == 0 || nd > 5 || *p != ' ') return nullptr;
  y = v;
  ++p;
  if (*p != '0' && *p != '1') return nullptr;
  pol = *p == '1' ? 1 : -1;
  ++p;
  if (*p == '\r') ++p;
  if (*p != '\n') return nullptr;
  t = sec * kNsPerSec + frac;
  return p + 1;
}

// A field ends at whitespace, a comma or the end of the line; anything else glued to a number
// ("12x", "3.5.1") makes the line malformed.
inline bool atFieldEnd(const char* p, const char* end) { return p == end || isSpace(*p); }

}  // namespace eds::text
