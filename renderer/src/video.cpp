#include "inhand/renderer/video.hpp"

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
#include <libavutil/error.h>
#include <libavutil/opt.h>
#include <libswscale/swscale.h>
}
#include <dlfcn.h>

#include <cstdint>

#include "inhand/core/error.hpp"

namespace inhand {

namespace {

// FFmpeg's libraries are opened when the first video is written, not when the process starts:
// with the 130 libraries their codecs pull in, the dynamic loader took 0.06 s of every command's
// start, most of which never write a video. The functions keep the headers' exact types
// (decltype), and the sonames come from the headers' major versions, so a build against another
// FFmpeg loads the libraries it was compiled for.
#define INHAND_SONAME(lib, major) "lib" #lib ".so." AV_STRINGIFY(major)
struct LibAv {
  decltype(&::av_strerror) av_strerror;
  decltype(&::av_log_set_level) av_log_set_level;
  decltype(&::av_d2q) av_d2q;
  decltype(&::av_opt_set) av_opt_set;
  decltype(&::av_frame_alloc) av_frame_alloc;
  decltype(&::av_frame_free) av_frame_free;
  decltype(&::av_frame_get_buffer) av_frame_get_buffer;
  decltype(&::av_frame_make_writable) av_frame_make_writable;
  decltype(&::av_packet_alloc) av_packet_alloc;
  decltype(&::av_packet_free) av_packet_free;
  decltype(&::av_packet_rescale_ts) av_packet_rescale_ts;
  decltype(&::avcodec_find_encoder_by_name) avcodec_find_encoder_by_name;
  decltype(&::avcodec_find_encoder) avcodec_find_encoder;
  decltype(&::avcodec_alloc_context3) avcodec_alloc_context3;
  decltype(&::avcodec_free_context) avcodec_free_context;
  decltype(&::avcodec_open2) avcodec_open2;
  decltype(&::avcodec_parameters_from_context) avcodec_parameters_from_context;
  decltype(&::avcodec_send_frame) avcodec_send_frame;
  decltype(&::avcodec_receive_packet) avcodec_receive_packet;
  decltype(&::avformat_alloc_output_context2) avformat_alloc_output_context2;
  decltype(&::avformat_new_stream) avformat_new_stream;
  decltype(&::avformat_write_header) avformat_write_header;
  decltype(&::avformat_free_context) avformat_free_context;
  decltype(&::av_interleaved_write_frame) av_interleaved_write_frame;
  decltype(&::av_write_trailer) av_write_trailer;
  decltype(&::avio_open) avio_open;
  decltype(&::avio_closep) avio_closep;
  decltype(&::sws_getContext) sws_getContext;
  decltype(&::sws_scale) sws_scale;
  decltype(&::sws_freeContext) sws_freeContext;
};

void* OpenLibrary(const char* soname) {
  void* handle = dlopen(soname, RTLD_NOW | RTLD_LOCAL);
  if (!handle) {
    const char* why = dlerror();
    throw InputError(std::string("cannot load FFmpeg's ") + soname + " to write MP4 video: " +
                     (why ? why : "unknown error") + " (scripts/install-deps.sh installs it)");
  }
  return handle;
}

template <typename Function>
void Resolve(void* library, const char* soname, const char* name, Function& function) {
  function = reinterpret_cast<Function>(dlsym(library, name));
  if (!function)
    throw InputError(std::string(soname) + " has no " + name +
                     ": not the FFmpeg this was built for");
}

LibAv LoadLibAv() {
  // Each library is loaded once per process and never closed (the handles outlive every writer).
  const char* util_name = INHAND_SONAME(avutil, LIBAVUTIL_VERSION_MAJOR);
  const char* codec_name = INHAND_SONAME(avcodec, LIBAVCODEC_VERSION_MAJOR);
  const char* format_name = INHAND_SONAME(avformat, LIBAVFORMAT_VERSION_MAJOR);
  const char* scale_name = INHAND_SONAME(swscale, LIBSWSCALE_VERSION_MAJOR);
  void* util = OpenLibrary(util_name);
  void* codec = OpenLibrary(codec_name);
  void* format = OpenLibrary(format_name);
  void* scale = OpenLibrary(scale_name);
  LibAv av{};
#define INHAND_RESOLVE(library, function) Resolve(library, library##_name, #function, av.function)
  INHAND_RESOLVE(util, av_strerror);
  INHAND_RESOLVE(util, av_log_set_level);
  INHAND_RESOLVE(util, av_d2q);
  INHAND_RESOLVE(util, av_opt_set);
  INHAND_RESOLVE(util, av_frame_alloc);
  INHAND_RESOLVE(util, av_frame_free);
  INHAND_RESOLVE(util, av_frame_get_buffer);
  INHAND_RESOLVE(util, av_frame_make_writable);
  INHAND_RESOLVE(codec, av_packet_alloc);
  INHAND_RESOLVE(codec, av_packet_free);
  INHAND_RESOLVE(codec, av_packet_rescale_ts);
  INHAND_RESOLVE(codec, avcodec_find_encoder_by_name);
  INHAND_RESOLVE(codec, avcodec_find_encoder);
  INHAND_RESOLVE(codec, avcodec_alloc_context3);
  INHAND_RESOLVE(codec, avcodec_free_context);
  INHAND_RESOLVE(codec, avcodec_open2);
  INHAND_RESOLVE(codec, avcodec_parameters_from_context);
  INHAND_RESOLVE(codec, avcodec_send_frame);
  INHAND_RESOLVE(codec, avcodec_receive_packet);
  INHAND_RESOLVE(format, avformat_alloc_output_context2);
  INHAND_RESOLVE(format, avformat_new_stream);
  INHAND_RESOLVE(format, avformat_write_header);
  INHAND_RESOLVE(format, avformat_free_context);
  INHAND_RESOLVE(format, av_interleaved_write_frame);
  INHAND_RESOLVE(format, av_write_trailer);
  INHAND_RESOLVE(format, avio_open);
  INHAND_RESOLVE(format, avio_closep);
  INHAND_RESOLVE(scale, sws_getContext);
  INHAND_RESOLVE(scale, sws_scale);
  INHAND_RESOLVE(scale, sws_freeContext);
#undef INHAND_RESOLVE
  return av;
}
#undef INHAND_SONAME

// The first call loads the libraries (thread-safe); a failure throws and the next call retries.
const LibAv& Av() {
  static const LibAv av = LoadLibAv();
  return av;
}

std::string AvError(const LibAv& av, int code) {
  char text[AV_ERROR_MAX_STRING_SIZE] = {0};
  av.av_strerror(code, text, sizeof(text));
  return text;
}

}  // namespace

// libavformat (MP4) + libavcodec (libx264, preset "veryfast", CRF 23, one thread: the replay
// runs its own threads beside it) + libswscale (RGB -> YUV 4:2:0).
struct VideoWriter::Impl {
  const LibAv& av = Av();
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
    if (code < 0) throw InputError(path + ": " + what + ": " + AvError(av, code));
  }
  // Sends a frame (nullptr: flush) and writes every packet the encoder has ready.
  void Encode(AVFrame* f) {
    Check(av.avcodec_send_frame(codec, f), "H.264 encoding failed");
    for (;;) {
      const int r = av.avcodec_receive_packet(codec, packet);
      if (r == AVERROR(EAGAIN) || r == AVERROR_EOF) return;
      Check(r, "H.264 encoding failed");
      av.av_packet_rescale_ts(packet, codec->time_base, stream->time_base);
      packet->stream_index = stream->index;
      Check(av.av_interleaved_write_frame(format, packet), "cannot write the video");
    }
  }
  void Free() {
    av.sws_freeContext(sws);
    sws = nullptr;
    av.av_frame_free(&frame);
    av.av_packet_free(&packet);
    av.avcodec_free_context(&codec);
    if (format) {
      if (format->pb) av.avio_closep(&format->pb);
      av.avformat_free_context(format);
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
  const LibAv& av = m.av;
  m.path = path;
  m.width = width;
  m.height = height;
  av.av_log_set_level(AV_LOG_ERROR);
  m.Check(av.avformat_alloc_output_context2(&m.format, nullptr, "mp4", path.c_str()),
          "cannot make an MP4 file");
  const AVCodec* encoder = av.avcodec_find_encoder_by_name("libx264");
  if (!encoder) encoder = av.avcodec_find_encoder(AV_CODEC_ID_H264);
  if (!encoder) throw InputError(path + ": this FFmpeg has no H.264 encoder");
  m.stream = av.avformat_new_stream(m.format, nullptr);
  m.codec = av.avcodec_alloc_context3(encoder);
  if (!m.stream || !m.codec) throw InputError(path + ": out of memory for the video encoder");
  const AVRational rate = av.av_d2q(fps, 100000);
  m.codec->width = width;
  m.codec->height = height;
  m.codec->time_base = av_inv_q(rate);
  m.codec->framerate = rate;
  m.codec->pix_fmt = AV_PIX_FMT_YUV420P;
  m.codec->gop_size = 30;
  m.codec->thread_count = 1;
  if (m.format->oformat->flags & AVFMT_GLOBALHEADER) m.codec->flags |= AV_CODEC_FLAG_GLOBAL_HEADER;
  av.av_opt_set(m.codec->priv_data, "preset", "veryfast", 0);
  av.av_opt_set(m.codec->priv_data, "crf", "23", 0);
  m.Check(av.avcodec_open2(m.codec, encoder, nullptr), "cannot open the H.264 encoder");
  m.Check(av.avcodec_parameters_from_context(m.stream->codecpar, m.codec),
          "cannot set the video stream");
  m.stream->time_base = m.codec->time_base;
  m.stream->avg_frame_rate = rate;
  m.Check(av.avio_open(&m.format->pb, path.c_str(), AVIO_FLAG_WRITE),
          "cannot open the video file for writing");
  m.Check(av.avformat_write_header(m.format, nullptr), "cannot write the video header");
  m.frame = av.av_frame_alloc();
  m.packet = av.av_packet_alloc();
  if (!m.frame || !m.packet) throw InputError(path + ": out of memory for the video encoder");
  m.frame->format = AV_PIX_FMT_YUV420P;
  m.frame->width = width;
  m.frame->height = height;
  m.Check(av.av_frame_get_buffer(m.frame, 0), "cannot allocate a video frame");
  m.sws = av.sws_getContext(width, height, AV_PIX_FMT_RGB24, width, height, AV_PIX_FMT_YUV420P,
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
  const LibAv& av = m.av;
  INHAND_CHECK(m.open, "VideoWriter::Write after Close");
  INHAND_CHECK(image.width == m.width && image.height == m.height && image.channels == 3,
               "video frames must be RGB of the writer's size");
  m.Check(av.av_frame_make_writable(m.frame), "cannot write a video frame");
  const std::uint8_t* src[1] = {image.data.data()};
  const int stride[1] = {3 * image.width};
  av.sws_scale(m.sws, src, stride, 0, image.height, m.frame->data, m.frame->linesize);
  m.frame->pts = m.next_pts++;
  m.Encode(m.frame);
  ++frames_;
}

void VideoWriter::Close() {
  if (!impl_ || !impl_->open) return;
  Impl& m = *impl_;
  const LibAv& av = m.av;
  m.open = false;
  m.Encode(nullptr);
  m.Check(av.av_write_trailer(m.format), "cannot finish the video");
  m.Free();
}

}  // namespace inhand
