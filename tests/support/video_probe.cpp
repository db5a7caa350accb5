#include "video_probe.hpp"

#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

namespace inhand::test {

VideoInfo ProbeVideo(const std::string& path) {
  VideoInfo info;
  cv::VideoCapture cap(path, cv::CAP_FFMPEG);
  if (!cap.isOpened()) return info;
  info.width = static_cast<int>(cap.get(cv::CAP_PROP_FRAME_WIDTH));
  info.height = static_cast<int>(cap.get(cv::CAP_PROP_FRAME_HEIGHT));
  info.fps = cap.get(cv::CAP_PROP_FPS);
  const int fourcc = static_cast<int>(cap.get(cv::CAP_PROP_FOURCC));
  for (int i = 0; i < 4; ++i) info.codec += static_cast<char>((fourcc >> (8 * i)) & 0xFF);
  // Count by decoding: container frame counts can be estimates.
  int n = 0;
  cv::Mat frame;
  while (cap.read(frame)) ++n;
  info.frames = n;
  return info;
}

Image8 ReadVideoFrame(const std::string& path, int index) {
  cv::VideoCapture cap(path, cv::CAP_FFMPEG);
  cv::Mat frame;
  for (int i = 0; i <= index; ++i)
    if (!cap.read(frame)) return Image8();
  Image8 out(frame.cols, frame.rows, 3);
  cv::Mat rgb(frame.rows, frame.cols, CV_8UC3, out.data.data());
  cv::cvtColor(frame, rgb, cv::COLOR_BGR2RGB);
  return out;
}

}  // namespace inhand::test
