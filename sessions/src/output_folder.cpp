#include "inhand/sessions/output_folder.hpp"

#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <fstream>

#include "inhand/core/error.hpp"

namespace fs = std::filesystem;

namespace inhand {

namespace {

fs::path Resolved(const std::string& path) {
  std::error_code ec;
  fs::path p = fs::weakly_canonical(fs::absolute(path), ec);
  if (ec) p = fs::absolute(path).lexically_normal();
  if (p.filename().empty() && p.has_parent_path() && p != p.root_path()) p = p.parent_path();
  return p;
}

// `a` is `b` or one of its ancestors.
bool Contains(const fs::path& a, const fs::path& b) {
  auto ai = a.begin(), bi = b.begin();
  for (; ai != a.end(); ++ai, ++bi)
    if (bi == b.end() || *ai != *bi) return false;
  return true;
}

// Why inhand may not replace `p`, or "" when it may.
std::string WhyNotReplaceable(const fs::path& p) {
  std::error_code ec;
  if (!fs::exists(p, ec)) return "";
  if (!fs::is_directory(p, ec)) return "is a file, not a folder";
  if (fs::exists(p / kOutputMarker, ec)) return "";
  if (fs::is_empty(p, ec)) return "";
  return "exists and was not written by inhand (it has no " + std::string(kOutputMarker) +
         "); choose another --out or empty it";
}

}  // namespace

fs::path CheckOutputFolder(const std::string& out, const std::vector<std::string>& inputs) {
  if (out.empty()) throw InputError("--out: empty path");
  const fs::path target = Resolved(out);
  if (target == target.root_path())
    throw InputError(out + ": the root folder cannot be an output folder");
  std::error_code ec;
  const fs::path cwd = Resolved(fs::current_path(ec).string());
  if (!ec && Contains(target, cwd))
    throw InputError(out + ": is the current folder or one of its ancestors (" + target.string() +
                     "); not replaced");
  for (const std::string& input : inputs) {
    if (input.empty()) continue;
    if (Contains(target, Resolved(input)))
      throw InputError(out + ": is the input " + input + " or one of its ancestors; not replaced");
  }
  if (const std::string why = WhyNotReplaceable(target); !why.empty())
    throw InputError(out + ": " + why);
  return target;
}

fs::path PrepareStaging(const fs::path& target) {
  const fs::path parent = target.parent_path();
  const std::string prefix = "." + target.filename().string() + ".tmp-";
  std::error_code ec;
  fs::create_directories(parent, ec);
  if (ec)
    throw InputError(parent.string() + ": cannot create the output's parent folder (" +
                     ec.message() + ")");
  for (const fs::directory_entry& e : fs::directory_iterator(parent, ec)) {
    const std::string name = e.path().filename().string();
    if (name.rfind(prefix, 0) != 0) continue;
    const std::string pid = name.substr(prefix.size());
    if (pid.empty() || pid.find_first_not_of("0123456789") != std::string::npos || pid.size() > 9)
      continue;
    const pid_t p = static_cast<pid_t>(std::stol(pid));
    if (p == ::getpid()) continue;
    if (::kill(p, 0) == 0 || errno == EPERM) continue;  // that run is still going
    std::error_code ignored;
    fs::remove_all(e.path(), ignored);
  }
  const fs::path staging = parent / (prefix + std::to_string(::getpid()));
  fs::remove_all(staging, ec);
  fs::create_directories(staging, ec);
  if (ec) throw InputError(staging.string() + ": cannot create (" + ec.message() + ")");
  return staging;
}

void CommitStaging(const fs::path& staging, const fs::path& target, const std::string& written_by) {
  std::ofstream(staging / kOutputMarker) << "written by inhand " << written_by << "\n";
  if (const std::string why = WhyNotReplaceable(target); !why.empty())
    throw InputError(target.string() + ": appeared while writing and " + why);
  std::error_code ec;
  fs::remove_all(target, ec);
  if (ec) throw InputError(target.string() + ": cannot replace (" + ec.message() + ")");
  fs::rename(staging, target, ec);
  if (ec)
    throw InputError(target.string() + ": cannot move the output into place (" + ec.message() +
                     ")");
}

}  // namespace inhand
