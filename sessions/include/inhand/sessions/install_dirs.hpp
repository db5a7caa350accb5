#pragma once
// Where the running inhand code lives, to find what is installed beside it: the project's
// assets (PREFIX/share/inhand/assets) and the plotting module (PREFIX/lib/python3.X/
// dist-packages, or build/python in the build tree).
#include <filesystem>

namespace inhand {

// The folder of the file holding this code: the inhand program (PREFIX/bin, build/bin), a
// program linking the libraries, or the Python module. Empty when it cannot be told.
std::filesystem::path RunningCodeDir();

}  // namespace inhand
