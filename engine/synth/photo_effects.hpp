#pragma once
// What a hand-held camera does to a photo that a renderer does not: the shake during the exposure.
#include <cstdint>

#include "engine/io/image.hpp"

namespace nf::synth {

// A horizontal motion blur over `length` pixels (odd; even lengths take the next odd one): the
// camera moving sideways while the shutter is open. Edges repeat the border pixel.
io::Image motion_blur(const io::Image& image, std::uint32_t length);

}  // namespace nf::synth
