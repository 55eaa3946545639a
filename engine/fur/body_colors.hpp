#pragma once
// A colour for every vertex of the bald body M_bald from the photos (issue 46: a body material, so
// that a render shows the animal where the coat parts, where it is thin and on bald skin, not a
// grey mesh under the strands).
//
// Under fur the skin is hidden; what shows through a parted coat is the fur's own colour. So each
// vertex takes the photo colour of the point of M_NeuS nearest it: the fur's outside over fur, the
// skin itself where M_NeuS and M_bald meet (nose, pads, the eyes). The colours come from the
// strand-colour pass (strand_colors.hpp) with one control per vertex, so the same views, mask and
// depth test, exposure gains and outlier rule apply; a vertex no view sees takes the mean of its
// nearest seen vertices. Written as fur/body_colors.npz (strand_colors.hpp's format, one "strand"
// per vertex, one control).
#include "engine/fur/strand_colors.hpp"

namespace nf::fur {

// One control per vertex of `bald`: the vertex as the root, the nearest point of `envelope` as the
// control, and as the "length" two of the envelope's mean edges: the depth test's tolerance (half
// of it, body_color_options) is then one mean edge, which a point on M_NeuS itself passes whatever the
// fur's depth, while a point behind another part of M_NeuS (a far leg) does not.
StrandControls body_color_points(const geometry::Mesh& bald, const geometry::Mesh& envelope);

// The strand options made the body's: one control, and `hidden_depth` 0.5 (see above). The fur
// stage colours these points in the groom's pass over the photos (color_control_sets), which gives
// per vertex of `bald` linear RGB (vertices x 1 x 3) and whether a view saw it.
StrandColorOptions body_color_options(StrandColorOptions options);

}  // namespace nf::fur
