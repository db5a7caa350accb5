#pragma once
// H.264 MP4 video written through FFmpeg's libraries (libx264, preset veryfast, CRF 23, fourcc
// avc1: plays everywhere), read back through OpenCV's FFmpeg backend.
#include <memory>
#include <string>

#include "inhand/core/image.hpp"

namespace inhand {

class VideoWriter {
 public:
  // Throws InputError when the file cannot be opened for H.264 encoding.
  VideoWriter(const std::string& path, double fps, int width, int height);
  ~VideoWriter();
  VideoWriter(const VideoWriter&) = delete;
  VideoWriter& operator=(const VideoWriter&) = delete;
  // Frames must have the size given at construction (RGB).
  void Write(const Image8& frame);
  void Close();
  int frames() const { return frames_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  int frames_ = 0;
};

}  // namespace inhand
