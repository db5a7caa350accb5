#pragma once
// Output folders (every --out): written under a hidden staging name beside the target, marked
// as inhand's and renamed into place. A target may be replaced only when it does not exist, is
// an empty folder, or was written by inhand (it holds the marker file); never when it is the
// current directory or one of its ancestors, or an input of the command or one of its
// ancestors. Staging folders left by a crashed run are removed by the next one.
#include <filesystem>
#include <string>
#include <vector>

namespace inhand {

inline constexpr const char* kOutputMarker = ".inhand-output";

// `out` resolved (absolute; `.`, `..` and symbolic links resolved) once it is known that it may
// be replaced. `inputs`: the files and folders the command reads. Throws InputError naming the
// folder and why.
std::filesystem::path CheckOutputFolder(const std::string& out,
                                        const std::vector<std::string>& inputs = {});
// `.NAME.tmp-PID` beside `target`, for this process; stale ones of ended processes are removed.
std::filesystem::path PrepareStaging(const std::filesystem::path& target);
// Writes the marker into `staging` and renames it to `target`, replacing `target` only when it
// still may be replaced (it can have appeared meanwhile). Throws InputError.
void CommitStaging(const std::filesystem::path& staging, const std::filesystem::path& target,
                   const std::string& written_by);

}  // namespace inhand
