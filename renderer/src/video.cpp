#include "inhand/renderer/video.hpp"

#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "inhand/core/error.hpp"

namespace inhand {

struct VideoWriter::Impl {
  cv::VideoWriter writer;
  int width = 0, height = 0;
  cv::Mat bgr;
};

VideoWriter::VideoWriter(const std::string& path, double fps, int width, int height) : impl_(std::make_unique<Impl>()) {
  if (width % 2 || height % 2) throw InputError(path + ": H.264 needs even frame sizes, got " + std::to_string(width) + "x" + std::to_string(height));
  impl_->width = width;
  impl_->height = height;
  impl_->writer.open(path, cv::CAP_FFMPEG, cv::VideoWriter::fourcc('a', 'v', 'c', '1'), fps, cv::Size(width, height), true);
  if (!impl_->writer.isOpened()) throw InputError(path + ": cannot open an H.264 (avc1) video writer");
}

VideoWriter::~VideoWriter() { Close(); }

void VideoWriter::Write(const Image8& frame) {
  INHAND_CHECK(frame.width == impl_->width && frame.height == impl_->height && frame.channels == 3,
               "video frames must be RGB of the writer's size");
  const cv::Mat rgb(frame.height, frame.width, CV_8UC3, const_cast<std::uint8_t*>(frame.data.data()));
  cv::cvtColor(rgb, impl_->bgr, cv::COLOR_RGB2BGR);
  impl_->writer.write(impl_->bgr);
  ++frames_;
}

void VideoWriter::Close() {
  if (impl_ && impl_->writer.isOpened()) impl_->writer.release();
}

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

}  // namespace inhand
