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

inline bool parseFloat(const char* s, float* out) {
  if (!s || !*s) return false;
  char* end = nullptr;
  double v = std::strtod(s, &end);
  if (*end) return false;
  *out = float(v);
  return true;
}

}  // namespace canopy::cli
