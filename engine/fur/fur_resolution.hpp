#pragma once
// Whether a photo resolves the fur, and how much the image losses may pull on it. The silhouette
// and orientation losses compare strands with the photos' masks and Gabor orientation maps. When a
// strand spans a pixel or two of the photo, the Gabor filters answer shading and outline instead of
// fur and the fur's rim in the mask is a pixel wide; both losses then pull a right groom off the
// fur (a synth cat at 128 px, fur 1.3 px long: F(2 cm, 20°) 92 -> 45-69 in 100 image steps, 92-94
// without them; docs/fur-stage.md, "Small photos"). So each view's image losses are weighted by the
// fur's length in its photo's pixels, L:
//   weight = clamp(2 L / resolved_px - 1, 0, 1)
// 0 up to half of resolved_px, 1 from resolved_px on. The default, 4.8 px, is twice the Gabor
// filters' length along a strand (sigma_y 2.4 px): a shorter strand fills too little of them to set
// their orientation. Twice their width across (3.6 px) was measured too and let the demo's 256 px
// photos (fur 2.9 px) cost 7.7 points of F(2 cm, 20°) where 4.8 costs 1 (docs/fur-stage.md).
// resolved_px 0: every view weighs 1. Views of weight 0 are left out of the training views' draw,
// so the others are drawn more often than with every view in it. L is counted in the photo's
// pixels, where the Gabor maps are made; the silhouette is compared on the rendering grid
// (`fur.resolution`), which this does not look at.
#include <cstddef>

#include "engine/fur/fur_views.hpp"
#include "engine/fur/roots.hpp"

namespace nf::fur {

// The median over the roots that project into `view`'s crop (at most `samples` of them, evenly
// strided) of the root's fur length in photo pixels, length x focal / depth; 0 when none does.
double fur_length_pixels(const FurView& view, const Roots& roots, std::size_t samples = 4096);

double image_loss_weight(double fur_pixels, double resolved_px);

// How many Gabor scales (orientation_scales.hpp: the photo and its halvings) a view's native
// targets use, at most `most`: a halving only while the fur still spans 2 x resolved_px pixels in
// the halved photo. The Gabor bank fits strand texture a few pixels wide; strands are as wide as
// the photo is large, so a 2048 px photo of fur that spans 35 px needs the halved photo's map
// where a 1024 px one (17.5 px) does not, and a coarser map of unresolved fur (the demo's 2.9 px)
// reads the body's shading as coherent orientation (on the demo: 48 % of the fur's pixels took the
// halved map and the trained groom fell from 94.2 with one map to 82.4 at F(2 cm, 20°); docs/fur-stage.md).
std::uint32_t gabor_scales_for(double fur_pixels, double resolved_px, std::uint32_t most);

}  // namespace nf::fur
