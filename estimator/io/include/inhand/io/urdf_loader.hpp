#pragma once
// URDF → HandModel, through urdfdom. Mesh paths may be relative (to the URDF's folder),
// absolute, file:// or package://NAME/... (resolved through PackageMap).
#include <map>
#include <string>
#include <vector>

#include "inhand/core/hand_model.hpp"

namespace inhand {

struct PackageMap {
  std::map<std::string, std::string> dirs;  // package name → its root folder
  // Parses "NAME=DIR"; throws InputError on a malformed entry.
  void AddSpec(const std::string& spec);
};

struct HandLoadOptions {
  PackageMap packages;
  bool load_visual_meshes = true;  // false skips visual mesh files (faster, for estimation)
  // Collision meshes: one convex hull each (hands), or one hull per connected component
  // (objects, whose collision files are stored decompositions such as YCB's).
  bool collision_mesh_components = false;
};

// Resolves a resource URI found in `referrer` (a URDF or description file). Package search:
// the explicit map, then the referrer's folder and its parents named NAME (or holding NAME/),
// then $ROS_PACKAGE_PATH. Throws InputError naming the referrer and the URI when the package
// is unknown or the file does not exist.
std::string ResolveResource(const std::string& uri, const std::string& referrer,
                            const PackageMap& packages);

// Throws InputError for malformed XML (with line), URDF errors (urdfdom's message), unsupported
// joint types, unresolvable or unreadable meshes.
HandModel LoadHandModel(const std::string& urdf_path, const HandLoadOptions& options = {});

// The same from a string; relative paths resolve against `base_dir`, messages name `source`.
HandModel ParseHandModel(const std::string& urdf_xml, const std::string& base_dir,
                         const std::string& source, const HandLoadOptions& options = {});

}  // namespace inhand
