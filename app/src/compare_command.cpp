#include <algorithm>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <set>
#include <sstream>
#include <vector>

#include "inhand/app/commands.hpp"
#include "inhand/core/error.hpp"
#include "inhand/renderer/image_compare.hpp"
#include "inhand/sessions/image_io.hpp"

namespace inhand::app {

namespace {

namespace fs = std::filesystem;

std::string Percent(double fraction) {
  std::ostringstream s;
  s << std::setprecision(4) << 100.0 * fraction << " %";
  return s.str();
}

// The PNG files directly in `dir`, by name.
std::set<std::string> PngNames(const std::string& dir) {
  std::set<std::string> names;
  for (const fs::directory_entry& e : fs::directory_iterator(dir))
    if (e.is_regular_file() && e.path().extension() == ".png")
      names.insert(e.path().filename().string());
  return names;
}

// Two folders of frames (replay --frames of two versions): pairwise by file name, each pair
// with the same two-number tolerance; frames present on one side only count as differing.
int CompareFolders(const CompareCommand& cmd) {
  const std::set<std::string> a = PngNames(cmd.a), b = PngNames(cmd.b);
  if (a.empty()) throw InputError("compare: " + cmd.a + " holds no PNG frames");
  if (b.empty()) throw InputError("compare: " + cmd.b + " holds no PNG frames");
  if (!cmd.diff.empty()) {
    if (fs::exists(cmd.diff) && !fs::is_directory(cmd.diff))
      throw InputError("--diff " + cmd.diff +
                       ": comparing folders, expected a folder for the heat maps");
    fs::create_directories(cmd.diff);
  }
  struct Result {
    std::string name;
    double bad_fraction;
    int max_delta;
    std::string note;
  };
  std::vector<Result> differ;
  int compared = 0;
  for (const std::string& name : a) {
    if (!b.count(name)) {
      differ.push_back({name, 1.0, 255, "only in " + cmd.a});
      continue;
    }
    const Image8 ia = ReadImage((fs::path(cmd.a) / name).string());
    const Image8 ib = ReadImage((fs::path(cmd.b) / name).string());
    ++compared;
    if (ia.width != ib.width || ia.height != ib.height || ia.channels != ib.channels) {
      differ.push_back({name, 1.0, 255,
                        std::to_string(ia.width) + "x" + std::to_string(ia.height) +
                            " px against " + std::to_string(ib.width) + "x" +
                            std::to_string(ib.height)});
      continue;
    }
    const ImageDiff d = CompareImages(ia, ib, cmd.max_channel_delta);
    if (d.bad_fraction <= cmd.max_bad_fraction) continue;
    differ.push_back({name, d.bad_fraction, d.max_channel_delta, ""});
    if (!cmd.diff.empty()) WriteImage((fs::path(cmd.diff) / name).string(), d.heatmap);
  }
  for (const std::string& name : b)
    if (!a.count(name)) differ.push_back({name, 1.0, 255, "only in " + cmd.b});
  std::stable_sort(differ.begin(), differ.end(), [](const Result& x, const Result& y) {
    return x.bad_fraction > y.bad_fraction ||
           (x.bad_fraction == y.bad_fraction && x.max_delta > y.max_delta);
  });
  std::cout << (differ.empty() ? "match" : "DIFFER") << ": " << compared
            << " frame pairs compared, " << differ.size()
            << " differ (a pixel is bad beyond a channel delta of " << cmd.max_channel_delta
            << "; allowed " << Percent(cmd.max_bad_fraction) << " bad pixels per frame)\n";
  for (std::size_t i = 0; i < differ.size() && i < 10; ++i) {
    const Result& r = differ[i];
    std::cout << "  " << r.name << ": ";
    if (!r.note.empty())
      std::cout << r.note << "\n";
    else
      std::cout << Percent(r.bad_fraction) << " bad, max channel delta " << r.max_delta << "\n";
  }
  if (differ.size() > 10) std::cout << "  ... and " << differ.size() - 10 << " more\n";
  return differ.empty() ? 0 : 1;
}

}  // namespace

int RunCompare(const CompareCommand& cmd) {
  if (cmd.max_channel_delta < 0 || cmd.max_channel_delta > 255)
    throw InputError("--max-channel-delta is " + std::to_string(cmd.max_channel_delta) +
                     ", expected 0..255");
  if (!(cmd.max_bad_fraction >= 0.0 && cmd.max_bad_fraction <= 1.0))
    throw InputError("--max-bad-fraction is " + std::to_string(cmd.max_bad_fraction) +
                     ", expected 0..1");
  const bool dir_a = fs::is_directory(cmd.a), dir_b = fs::is_directory(cmd.b);
  if (dir_a && dir_b) return CompareFolders(cmd);
  if (dir_a != dir_b)
    throw InputError("compare: " + (dir_a ? cmd.a : cmd.b) + " is a folder and " +
                     (dir_a ? cmd.b : cmd.a) + " is not: give two images or two folders of frames");
  const Image8 a = ReadImage(cmd.a);
  const Image8 b = ReadImage(cmd.b);
  if (a.width != b.width || a.height != b.height || a.channels != b.channels)
    throw InputError("compare: " + cmd.a + " is " + std::to_string(a.width) + "x" +
                     std::to_string(a.height) + " px, " + cmd.b + " is " + std::to_string(b.width) +
                     "x" + std::to_string(b.height) + " px: images of different sizes");
  const ImageDiff d = CompareImages(a, b, cmd.max_channel_delta);
  if (!cmd.diff.empty()) WriteImage(cmd.diff, d.heatmap);
  const bool match = d.bad_fraction <= cmd.max_bad_fraction;
  std::cout << (match ? "match" : "DIFFER") << ": max channel delta " << d.max_channel_delta << ", "
            << d.bad_pixels << " pixels (" << Percent(d.bad_fraction) << ") differ by more than "
            << cmd.max_channel_delta << " (allowed " << Percent(cmd.max_bad_fraction) << ")\n";
  return match ? 0 : 1;
}

}  // namespace inhand::app
