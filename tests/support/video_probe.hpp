#pragma once
// Reading the videos inhand writes, for tests: through OpenCV's FFmpeg backend, a decoder that is
// not ours (inhand writes them through FFmpeg's libraries). Kept out of the libraries so that the
// inhand command does not load OpenCV's videoio (~70 ms of its start-up).
#include <string>

#include "inhand/core/image.hpp"

namespace inhand::test {

// Frames (counted by decoding: container counts can be estimates), size, rate and codec of a
// video file; frames = -1 when unreadable.
struct VideoInfo {
  int frames = -1;
  int width = 0, height = 0;
  double fps = 0.0;
  std::string codec;  // fourcc as text, e.g. "h264"
};
VideoInfo ProbeVideo(const std::string& path);
// Decodes frame `index` (RGB); empty image when unavailable.
Image8 ReadVideoFrame(const std::string& path, int index);

}  // namespace inhand::test
