#pragma once
// A progress line for long work (generating, loading, preprocessing a big scene): counts and rate
// on one line of stderr, rewritten in place on a terminal, at most one line per second otherwise.
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <string>
#include <unistd.h>

namespace canopy::cli {

class ProgressLine {
 public:
  explicit ProgressLine(std::string what) : what_(std::move(what)), tty_(isatty(2)), start_(Clock::now()) {}
  // (stage, done, total): the signature of SceneProgress.
  void operator()(const char* stage, uint64_t done, uint64_t total) {
    const auto now = Clock::now();
    if (stage_ != stage) {  // a new stage: its own rate and clock
      stage_ = stage;
      start_ = now;
      printed_ = {};
    }
    const double s = std::chrono::duration<double>(now - start_).count();
    const bool last = done >= total;
    if (!last && !tty_ && std::chrono::duration<double>(now - printed_).count() < 1.0) return;
    printed_ = now;
    std::fprintf(stderr, "%s%s: %s %s / %s (%s/s, %.1f s)%s", tty_ ? "\r" : "", what_.c_str(), stage, human(done).c_str(),
                 human(total).c_str(), human(uint64_t(s > 0 ? double(done) / s : 0)).c_str(), s, last || !tty_ ? "\n" : "");
    std::fflush(stderr);
  }

 private:
  using Clock = std::chrono::steady_clock;
  static std::string human(uint64_t v) {
    char b[32];
    if (v >= 1'000'000) std::snprintf(b, sizeof b, "%.2fM", double(v) / 1e6);
    else if (v >= 10'000) std::snprintf(b, sizeof b, "%.1fK", double(v) / 1e3);
    else std::snprintf(b, sizeof b, "%llu", (unsigned long long)v);
    return b;
  }
  std::string what_, stage_;
  bool tty_;
  Clock::time_point start_, printed_{};
};

}  // namespace canopy::cli
