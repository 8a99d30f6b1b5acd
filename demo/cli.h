#pragma once
// Strict number parsing for the command-line programs (demo/, bench/): the whole argument must be
// a number in range, otherwise the caller prints a one-line reason.
#include <cstdint>
#include <cstdlib>

namespace canopy::cli {

inline bool parseUint(const char* s, uint64_t lo, uint64_t hi, uint32_t* out) {
  if (!s || !*s) return false;
  char* end = nullptr;
  long long v = std::strtoll(s, &end, 10);
  if (*end || v < 0 || uint64_t(v) < lo || uint64_t(v) > hi) return false;
  *out = uint32_t(v);
  return true;
}

// A count with an optional K (1e3) or M (1e6) suffix: "80000", "80K", "50M".
inline bool parseCount(const char* s, uint64_t lo, uint64_t hi, uint64_t* out) {
  if (!s || !*s) return false;
  char* end = nullptr;
  const double v = std::strtod(s, &end);
  double scale = 1;
  if (*end == 'K' || *end == 'k') scale = 1e3, ++end;
  else if (*end == 'M' || *end == 'm') scale = 1e6, ++end;
  if (*end || !(v >= 0)) return false;
  const double r = v * scale;
  if (r < double(lo) || r > double(hi) || r != double(uint64_t(r))) return false;
  *out = uint64_t(r);
  return true;
}

inline bool parseFloat(const char* s, float* out) {
  if (!s || !*s) return false;
  char* end = nullptr;
  double v = std::strtod(s, &end);
  if (*end) return false;
  *out = float(v);
  return true;
}

}  // namespace canopy::cli
