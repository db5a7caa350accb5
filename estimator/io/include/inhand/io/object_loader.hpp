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

// How the object's signed distance field for contacts is made (object JSON: "contact_field").
//   source "auto":   none for a single convex piece (GJK is exact), else the closed visual
//                    meshes if they are watertight (a scan), else the union of the pieces;
//          "visual": the visual meshes (an error if they have holes); "pieces": their union;
//          "none":   per-piece GJK (the deepest piece pair: wrong on fragmented decompositions).
// Built once (about a second for a 16k-triangle scan at 1 mm) and cached on disk, keyed by the
// geometry and the parameters, in CacheDirectory(cache_dir) as sdf-<hash>.bin.
struct ContactFieldOptions {
  std::string source = "auto";
  DistanceFieldParams params;
  std::string cache_dir;  // "" -> CacheDirectory()
  void Validate(const std::string& where) const;
};

ObjectModel LoadObjectModel(const std::string& path, const PackageMap& packages = {});
// As LoadObjectModel, with the contact field chosen by `field` instead of the description's
// own setting (for the URDF path, which has none, and for tools).
ObjectModel LoadObjectModel(const std::string& path, const PackageMap& packages,
                            const ContactFieldOptions& field);

// "visual", "pieces" or "none": what `options` selects for `obj`.
std::string ResolveContactFieldSource(const ObjectModel& obj, const ContactFieldOptions& options,
                                      const std::string& where);
// Builds (or reads from the cache) and sets obj.field / obj.field_cache.
void AttachContactField(ObjectModel& obj, const ContactFieldOptions& options,
                        const std::string& where);

}  // namespace inhand
