#pragma once
// Object descriptions → ObjectModel. Two formats:
//  - inhand's object JSON (assets/objects/*/object.json, documented in assets/README.md):
//    visual meshes, collision pieces (a decomposition file, connected components or convex hull
//    of a mesh, HACD, or primitives), mass, optional inertia, friction, AprilTag placements;
//  - a single-link URDF (e.g. the YCB objects): visual + collision elements and <inertial>.
#include <string>

#include "inhand/core/object_model.hpp"
#include "inhand/io/urdf_loader.hpp"

namespace inhand {

ObjectModel LoadObjectModel(const std::string& path, const PackageMap& packages = {});

}  // namespace inhand
