#pragma once
// The headless demo's PNG files written on a worker thread, so the frame loop measures Canopy's
// frames and not the PNG encoder (docs/performance.md: a 1024x768 PNG costs more than a still
// frame). At most `depth` frames wait; a push beyond that waits for the worker. The time the worker
// spends per file is kept and reported apart from the frame times.
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "engine/status.h"

namespace canopy::demo {

class FrameWriter {
 public:
  explicit FrameWriter(size_t depth = 4);
  ~FrameWriter();
  FrameWriter(const FrameWriter&) = delete;
  FrameWriter& operator=(const FrameWriter&) = delete;
  // Queues `rgba` (width x height RGBA8) for `path`; an earlier write's error is returned here.
  Status push(std::string path, uint32_t width, uint32_t height, std::vector<uint8_t> rgba);
  // Waits for every queued file; the first error, if any.
  Status finish();
  // Milliseconds each written file took the worker (encode + write).
  std::vector<double> writeMs() const;

 private:
  struct Job {
    std::string path;
    uint32_t width = 0, height = 0;
    std::vector<uint8_t> rgba;
  };
  void run();
  const size_t depth_;
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<Job> jobs_;
  bool busy_ = false, stop_ = false;
  Status error_;
  std::vector<double> ms_;
  std::thread worker_;
};

}  // namespace canopy::demo
