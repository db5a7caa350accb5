#pragma once
// Where the running inhand code lives, to find what is installed beside it: the project's
// assets (PREFIX/share/inhand/assets) and the plotting module (PREFIX/lib/python3.X/
// dist-packages, or build/python in the build tree).
#include <filesystem>
#include <vector>

namespace inhand {

// The folder of the file holding this code: the inhand program (PREFIX/bin, build/bin), a
// program linking the libraries, or the Python module. Empty when it cannot be told.
std::filesystem::path RunningCodeDir();

// Where an installed `relative` path (e.g. "share/inhand/assets", "bin/inhand") would be, seen
// from the running code: PREFIX/relative for code in PREFIX/bin (the program) and for code in
// PREFIX/lib/python3.X/dist-packages (the Python module), the build tree's build/relative from
// build/bin. Both candidates, normalised, whether they exist or not; none when the running code
// cannot be told.
std::vector<std::filesystem::path> BesideRunningCode(const std::filesystem::path& relative);

}  // namespace inhand
