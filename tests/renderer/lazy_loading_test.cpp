// A binary of its own that links nothing but the renderer: the test binaries that read videos
// back link OpenCV's videoio, which maps FFmpeg at start.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "inhand/core/error.hpp"
#include "inhand/renderer/osmesa.hpp"
#include "inhand/renderer/renderer.hpp"
#include "inhand/renderer/video.hpp"
#include "test_support.hpp"

namespace inhand {
namespace {

// Whether a shared library whose file name contains `name` is mapped into this process.
bool Mapped(const std::string& name) {
  std::ifstream maps("/proc/self/maps");
  for (std::string line; std::getline(maps, line);)
    if (line.find(name) != std::string::npos) return true;
  return false;
}

// ctest runs every test in a process of its own: this one starts with nothing rendered.
TEST(LazyLoading, OsMesaAndFfmpegAreLoadedOnlyWhenFirstUsed) {
  ASSERT_FALSE(Mapped("libOSMesa")) << "OSMesa is loaded before anything renders";
  ASSERT_FALSE(Mapped("libavcodec")) << "FFmpeg is loaded before any video is written";
  {
    Renderer r;
    EXPECT_NE(r.Description().find("llvmpipe"), std::string::npos) << r.Description();
  }
  EXPECT_TRUE(Mapped("libOSMesa"));
  EXPECT_FALSE(Mapped("libavcodec"));
  const test::TempDir dir;
  const std::string path = dir / "lazy.mp4";
  {
    VideoWriter video(path, 10.0, 64, 48);
    video.Write(Image8(64, 48, 3));
  }
  EXPECT_TRUE(Mapped("libavcodec"));
  EXPECT_GT(std::filesystem::file_size(path), 0u);
}

TEST(LazyLoading, AMissingOsMesaFunctionIsNamed) {
  try {
    OsMesaFunction("OSMesaNoSuchFunction");
    ADD_FAILURE() << "a missing OSMesa function was not refused";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("OSMesaNoSuchFunction"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace inhand
