#pragma once
// Strict number parsing for the command-line programs (demo/, bench/): the whole argument must be
// a number in range, otherwise the caller prints a one-line reason.
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

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

// "a,b,c" -> {"a", "b", "c"} (empty items kept, so "a,,b" is refused by whoever checks names).
inline std::vector<std::string> splitList(const std::string& s) {
  std::vector<std::string> out;
  size_t start = 0;
  while (start <= s.size()) {
    const size_t comma = std::min(s.find(',', start), s.size());
    out.push_back(s.substr(start, comma - start));
    start = comma + 1;
  }
  return out;
}

// A "Key: N kB" line of a /proc file, in bytes (0 when unknown).
inline uint64_t procKilobytes(const char* path, const char* key) {
  uint64_t kb = 0;
  if (FILE* f = std::fopen(path, "r")) {
    char line[256];
    const size_t n = std::strlen(key);
    while (std::fgets(line, sizeof line, f))
      if (std::strncmp(line, key, n) == 0 && line[n] == ':' && std::sscanf(line + n + 1, "%lu", (unsigned long*)&kb) == 1) break;
    std::fclose(f);
  }
  return kb * 1024;
}

// MemAvailable of /proc/meminfo: the memory a big request may use before the kernel's OOM killer
// ends the process, which no bad_alloc would report.
inline uint64_t availableMemoryBytes() { return procKilobytes("/proc/meminfo", "MemAvailable"); }

// The peak before the last resetPeakResident(), so peakResidentBytes() stays the whole run's.
inline uint64_t& carriedPeakBytes() {
  static uint64_t peak = 0;
  return peak;
}

// The process's peak resident memory (VmHWM of /proc/self/status, and any peak before a reset). On
// a CPU driver (lavapipe) device memory is host memory too, so this includes it.
inline uint64_t peakResidentBytes() {
  return std::max(carriedPeakBytes(), procKilobytes("/proc/self/status", "VmHWM"));
}

// The resident memory now (VmRSS).
inline uint64_t residentBytes() { return procKilobytes("/proc/self/status", "VmRSS"); }

// Restarts VmHWM at the current resident size (Linux: "5" to /proc/self/clear_refs), so the peak
// of one step can be read alone; false where the kernel does not allow it.
inline bool resetPeakResident() {
  carriedPeakBytes() = peakResidentBytes();
  FILE* f = std::fopen("/proc/self/clear_refs", "w");
  if (!f) return false;
  const bool ok = std::fputs("5", f) >= 0;
  return std::fclose(f) == 0 && ok;
}

}  // namespace canopy::cli
