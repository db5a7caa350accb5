#include <iomanip>
#include <iostream>

#include "inhand/app/commands.hpp"
#include "inhand/core/error.hpp"
#include "inhand/renderer/image_compare.hpp"
#include "inhand/renderer/image_io.hpp"

namespace inhand::app {

int RunCompare(const CompareCommand& cmd) {
  if (cmd.max_channel_delta < 0 || cmd.max_channel_delta > 255)
    throw InputError("--max-channel-delta is " + std::to_string(cmd.max_channel_delta) + ", expected 0..255");
  if (!(cmd.max_bad_fraction >= 0.0 && cmd.max_bad_fraction <= 1.0))
    throw InputError("--max-bad-fraction is " + std::to_string(cmd.max_bad_fraction) + ", expected 0..1");
  const Image8 a = ReadImage(cmd.a);
  const Image8 b = ReadImage(cmd.b);
  if (a.width != b.width || a.height != b.height || a.channels != b.channels)
    throw InputError("compare: " + cmd.a + " is " + std::to_string(a.width) + "x" + std::to_string(a.height) + " px, " + cmd.b +
                     " is " + std::to_string(b.width) + "x" + std::to_string(b.height) + " px: images of different sizes");
  const ImageDiff d = CompareImages(a, b, cmd.max_channel_delta);
  if (!cmd.diff.empty()) WriteImage(cmd.diff, d.heatmap);
  const bool match = d.bad_fraction <= cmd.max_bad_fraction;
  std::cout << (match ? "match" : "DIFFER") << ": max channel delta " << d.max_channel_delta << ", "
            << d.bad_pixels << " pixels (" << std::setprecision(4) << 100.0 * d.bad_fraction
            << " %) differ by more than " << cmd.max_channel_delta << " (allowed "
            << 100.0 * cmd.max_bad_fraction << " %)\n";
  return match ? 0 : 1;
}

}  // namespace inhand::app
