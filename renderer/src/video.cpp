#include "inhand/renderer/video.hpp"

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
#include <libavutil/error.h>
#include <libavutil/opt.h>
#include <libswscale/swscale.h>
}

#include <cstdint>

#include "inhand/core/error.hpp"

namespace inhand {

namespace {

std::string AvError(int code) {
  char text[AV_ERROR_MAX_STRING_SIZE] = {0};
  av_strerror(code, text, sizeof(text));
  return text;
}

}  // namespace

// libavformat (MP4) + libavcodec (libx264, preset "veryfast", CRF 23, one thread: the replay
// runs its own threads beside it) + libswscale (RGB -> YUV 4:2:0).
struct VideoWriter::Impl {
  std::string path;
  int width = 0, height = 0;
  AVFormatContext* format = nullptr;
  AVCodecContext* codec = nullptr;
  AVStream* stream = nullptr;
  SwsContext* sws = nullptr;
  AVFrame* frame = nullptr;
  AVPacket* packet = nullptr;
  std::int64_t next_pts = 0;
  bool open = false;

  void Check(int code, const char* what) const {
    if (code < 0) throw InputError(path + ": " + what + ": " + AvError(code));
  }
  // Sends a frame (nullptr: flush) and writes every packet the encoder has ready.
  void Encode(AVFrame* f) {
    Check(avcodec_send_frame(codec, f), "H.264 encoding failed");
    for (;;) {
      const int r = avcodec_receive_packet(codec, packet);
      if (r == AVERROR(EAGAIN) || r == AVERROR_EOF) return;
      Check(r, "H.264 encoding failed");
      av_packet_rescale_ts(packet, codec->time_base, stream->time_base);
      packet->stream_index = stream->index;
      Check(av_interleaved_write_frame(format, packet), "cannot write the video");
    }
  }
  void Free() {
    sws_freeContext(sws);
    sws = nullptr;
    av_frame_free(&frame);
    av_packet_free(&packet);
    avcodec_free_context(&codec);
    if (format) {
      if (format->pb) avio_closep(&format->pb);
      avformat_free_context(format);
      format = nullptr;
    }
  }
  ~Impl() { Free(); }
};

VideoWriter::VideoWriter(const std::string& path, double fps, int width, int height)
    : impl_(std::make_unique<Impl>()) {
  if (width % 2 || height % 2)
    throw InputError(path + ": H.264 needs even frame sizes, got " + std::to_string(width) + "x" +
                     std::to_string(height));
  if (!(fps > 0.0 && fps <= 1000.0))
    throw InputError(path + ": video frame rate " + std::to_string(fps) +
                     " Hz, expected (0, 1000]");
  Impl& m = *impl_;
  m.path = path;
  m.width = width;
  m.height = height;
  av_log_set_level(AV_LOG_ERROR);
  m.Check(avformat_alloc_output_context2(&m.format, nullptr, "mp4", path.c_str()),
          "cannot make an MP4 file");
  const AVCodec* encoder = avcodec_find_encoder_by_name("libx264");
  if (!encoder) encoder = avcodec_find_encoder(AV_CODEC_ID_H264);
  if (!encoder) throw InputError(path + ": this FFmpeg has no H.264 encoder");
  m.stream = avformat_new_stream(m.format, nullptr);
  m.codec = avcodec_alloc_context3(encoder);
  if (!m.stream || !m.codec) throw InputError(path + ": out of memory for the video encoder");
  const AVRational rate = av_d2q(fps, 100000);
  m.codec->width = width;
  m.codec->height = height;
  m.codec->time_base = av_inv_q(rate);
  m.codec->framerate = rate;
  m.codec->pix_fmt = AV_PIX_FMT_YUV420P;
  m.codec->gop_size = 30;
  m.codec->thread_count = 1;
  if (m.format->oformat->flags & AVFMT_GLOBALHEADER) m.codec->flags |= AV_CODEC_FLAG_GLOBAL_HEADER;
  av_opt_set(m.codec->priv_data, "preset", "veryfast", 0);
  av_opt_set(m.codec->priv_data, "crf", "23", 0);
  m.Check(avcodec_open2(m.codec, encoder, nullptr), "cannot open the H.264 encoder");
  m.Check(avcodec_parameters_from_context(m.stream->codecpar, m.codec),
          "cannot set the video stream");
  m.stream->time_base = m.codec->time_base;
  m.stream->avg_frame_rate = rate;
  m.Check(avio_open(&m.format->pb, path.c_str(), AVIO_FLAG_WRITE),
          "cannot open the video file for writing");
  m.Check(avformat_write_header(m.format, nullptr), "cannot write the video header");
  m.frame = av_frame_alloc();
  m.packet = av_packet_alloc();
  if (!m.frame || !m.packet) throw InputError(path + ": out of memory for the video encoder");
  m.frame->format = AV_PIX_FMT_YUV420P;
  m.frame->width = width;
  m.frame->height = height;
  m.Check(av_frame_get_buffer(m.frame, 0), "cannot allocate a video frame");
  m.sws = sws_getContext(width, height, AV_PIX_FMT_RGB24, width, height, AV_PIX_FMT_YUV420P,
                         SWS_BILINEAR, nullptr, nullptr, nullptr);
  if (!m.sws) throw InputError(path + ": cannot convert RGB to YUV");
  m.open = true;
}

VideoWriter::~VideoWriter() {
  try {
    Close();
  } catch (...) {  // a destructor does not throw; Close() reports to callers that call it
  }
}

void VideoWriter::Write(const Image8& image) {
  Impl& m = *impl_;
  INHAND_CHECK(m.open, "VideoWriter::Write after Close");
  INHAND_CHECK(image.width == m.width && image.height == m.height && image.channels == 3,
               "video frames must be RGB of the writer's size");
  m.Check(av_frame_make_writable(m.frame), "cannot write a video frame");
  const std::uint8_t* src[1] = {image.data.data()};
  const int stride[1] = {3 * image.width};
  sws_scale(m.sws, src, stride, 0, image.height, m.frame->data, m.frame->linesize);
  m.frame->pts = m.next_pts++;
  m.Encode(m.frame);
  ++frames_;
}

void VideoWriter::Close() {
  if (!impl_ || !impl_->open) return;
  Impl& m = *impl_;
  m.open = false;
  m.Encode(nullptr);
  m.Check(av_write_trailer(m.format), "cannot finish the video");
  m.Free();
}

}  // namespace inhand
