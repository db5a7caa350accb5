#pragma once
// AprilTags as printed on an object: its appearance in rendered images (the simulator's camera,
// the tracker's virtual image, the annotated frames). Bitmaps from libapriltag's family tables.
#include <vector>

#include "inhand/core/mesh.hpp"
#include "inhand/core/object_model.hpp"

namespace inhand {

// The tag's bitmap (white border included) as a textured quad in the tag frame (z = 0, facing
// +z). Throws InputError for an unknown family or id.
TriangleMesh MakeTagMesh(const TagPlacement& tag);
// The object's tags as printed on it: each tag's quad moved into the object frame, 0.2 mm off the
// surface (no z-fighting with it). For UploadObject's `printed`.
std::vector<TriangleMesh> PrintedTagMeshes(const ObjectModel& object);

}  // namespace inhand
