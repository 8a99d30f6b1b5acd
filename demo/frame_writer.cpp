#include "demo/frame_writer.h"

#include <chrono>

#include "tools/image_io.h"

namespace canopy::demo {

FrameWriter::FrameWriter(size_t depth) : depth_(depth ? depth : 1), worker_([this] { run(); }) {}

FrameWriter::~FrameWriter() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  changed_.notify_all();
  worker_.join();
}

Status FrameWriter::push(std::string path, uint32_t width, uint32_t height, std::vector<uint8_t> rgba) {
  std::unique_lock<std::mutex> lock(mutex_);
  changed_.wait(lock, [&] { return jobs_.size() < depth_ || !error_.ok(); });
  if (!error_.ok()) return error_;
  jobs_.push_back({std::move(path), width, height, std::move(rgba)});
  changed_.notify_all();
  return Status();
}

Status FrameWriter::finish() {
  std::unique_lock<std::mutex> lock(mutex_);
  changed_.wait(lock, [&] { return (jobs_.empty() && !busy_) || !error_.ok(); });
  return error_;
}

std::vector<double> FrameWriter::writeMs() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return ms_;
}

void FrameWriter::run() {
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    changed_.wait(lock, [&] { return stop_ || !jobs_.empty(); });
    if (jobs_.empty()) return;  // stopping with nothing left
    Job job = std::move(jobs_.front());
    jobs_.pop_front();
    busy_ = true;
    lock.unlock();
    const auto t0 = std::chrono::steady_clock::now();
    const Status s = writePng(job.path, job.width, job.height, job.rgba);
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    lock.lock();
    busy_ = false;
    ms_.push_back(ms);
    if (!s.ok() && error_.ok()) error_ = s;
    changed_.notify_all();
  }
}

}  // namespace canopy::demo
