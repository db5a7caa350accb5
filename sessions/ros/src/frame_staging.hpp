#pragma once
// Internal: camera frames of a recording encoded while it is read. Raw images become PNG files,
// PNG and JPEG messages are kept as they are; a pool of workers does it on every core into a
// staging folder beside the output, from which the session adopts the frames it keeps.
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <exception>
#include <filesystem>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "inhand/ros/messages.hpp"

namespace inhand::ros {

struct Encoded {
  std::vector<std::uint8_t> bytes;
  std::string extension;
  int width = 0, height = 0;
};

// The frame's file: raw images as PNG, PNG and JPEG messages as they are (after checking that
// they decode). Throws InputError naming `context` for an encoding or format it cannot take.
Encoded EncodeFrame(const Payload& payload, const std::string& context);

// An encoded frame waiting in the staging folder for its place in the session.
struct StagedFrame {
  std::string file, extension;
  int width = 0, height = 0;
};

// Workers that encode frames while the main thread reads the recording: a fixed pool (each
// keeps its encoder's scratch buffers warm), a bounded queue (the main thread waits when it is
// full), the first error rethrown by Drain().
class EncoderPool {
 public:
  using Job = std::function<void()>;
  explicit EncoderPool(unsigned threads) : capacity_(2 * threads) {
    for (unsigned i = 0; i < threads; ++i) workers_.emplace_back([this] { Work(); });
  }
  ~EncoderPool() {
    {
      std::lock_guard<std::mutex> lock(m_);
      stop_ = true;
    }
    ready_.notify_all();
    for (auto& w : workers_) w.join();
  }
  EncoderPool(const EncoderPool&) = delete;
  EncoderPool& operator=(const EncoderPool&) = delete;
  void Submit(Job job) {
    std::unique_lock<std::mutex> lock(m_);
    space_.wait(lock, [&] { return jobs_.size() < capacity_ || error_; });
    if (error_) std::rethrow_exception(error_);
    jobs_.push_back(std::move(job));
    ready_.notify_one();
  }
  void Drain() {
    std::unique_lock<std::mutex> lock(m_);
    space_.wait(lock, [&] { return (jobs_.empty() && busy_ == 0) || error_; });
    if (error_) std::rethrow_exception(error_);
  }

 private:
  void Work() {
    std::unique_lock<std::mutex> lock(m_);
    while (true) {
      ready_.wait(lock, [&] { return stop_ || !jobs_.empty(); });
      if (jobs_.empty()) return;  // stopping
      Job job = std::move(jobs_.front());
      jobs_.pop_front();
      ++busy_;
      space_.notify_all();
      lock.unlock();
      std::exception_ptr e;
      try {
        job();
      } catch (...) {
        e = std::current_exception();
      }
      lock.lock();
      --busy_;
      if (e && !error_) error_ = e;
      space_.notify_all();
    }
  }
  std::size_t capacity_;
  std::mutex m_;
  std::condition_variable ready_, space_;
  std::deque<Job> jobs_;
  int busy_ = 0;
  bool stop_ = false;
  std::exception_ptr error_;
  std::vector<std::thread> workers_;
};

// A folder beside the output for frames encoded while the recording is read; removed at the end.
class FrameStaging {
 public:
  explicit FrameStaging(const std::string& out);
  ~FrameStaging();
  FrameStaging(const FrameStaging&) = delete;
  FrameStaging& operator=(const FrameStaging&) = delete;
  // Writes the encoded frame of the image topic's message `message`; where it went.
  StagedFrame Stage(std::uint64_t message, const Encoded& e) const;

 private:
  std::filesystem::path dir_;
};

}  // namespace inhand::ros
