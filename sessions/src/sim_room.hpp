#pragma once
// Internal: what the simulator's camera sees besides the hand and the object: a wooden table, a
// cluttered wall, the scenario's props and a few objects on the table (with `occluders` of them
// between the camera and the grasp). The same room for every seed.
#include "inhand/renderer/renderer.hpp"
#include "scenarios.hpp"

namespace inhand::sim {

// Uploads the room's meshes to `renderer` and returns the scene with them placed, seen by `K`
// from `T_WC` (world frame), on the room's background colour.
Scene BuildRoom(Renderer& renderer, const Scenario& scenario, int occluders, const Intrinsics& K,
                const Transform& T_WC);

}  // namespace inhand::sim
