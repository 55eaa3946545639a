#pragma once
// A user's SMAL model (Zuffi et al. 2017), converted from the official .pkl by tools/smal_to_npz.py,
// loaded into the same BodyModel as the procedural family. Arrays read (SMAL's own names):
//   v_template (V, 3), f (F, 3), shapedirs (V, 3, S), J_regressor (J, V), kintree_table (2, J),
//   weights (V, J); posedirs is ignored (nf_gpu poses with plain linear blend skinning).
// J is 33 (SMAL) or 35 (SMALST, with ear joints). The joint template and its shape directions come
// from J_regressor; each vertex keeps its four strongest skinning weights.
// The model is turned into the animal frame (+x left, +y up, +z tail to head) from its own
// skeleton: the legs give up, head against tail gives forward, whatever axes the file uses. Regions need no painting: each vertex takes the part of its strongest joint, with the rules
// of the procedural family (pads face down, the belly faces down, under_tail around the tail root,
// the inner ear faces forward), and SMAL's keypoint vertices (eyes 3055 / 1097, nose tip 1863, ear
// tips 150 / 2124 of the 3889-vertex mesh) seed the eyes, nose tip and, without ear joints, ears.
#include <filesystem>
#include <string>
#include <vector>

#include "engine/body/body_model.hpp"

namespace nf::body {

// The joint names of SMAL's kinematic tree in file order (33, or 35 with the SMALST ears).
const std::vector<std::string>& smal_joint_names(std::size_t joints);

// Throws InputError naming the file and the array (missing, wrong shape, NaN, a parent after its
// child) when the file is not a SMAL model.
BodyModel load_smal_model(const std::filesystem::path& npz);

}  // namespace nf::body
