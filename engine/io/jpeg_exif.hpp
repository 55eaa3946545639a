#pragma once
// The EXIF a camera writes into its JPEGs, as much of it as structure-from-motion reads: the maker,
// the model and the focal length (in mm and as the 35 mm-film equivalent, which COLMAP turns into
// its first guess of the focal length in pixels).
#include <string>

namespace nf::io {

struct CameraExif {
  std::string make, model;
  double focal_length_mm = 0;     // the lens's own
  double focal_length_35mm = 0;   // the same field of view on 36 x 24 mm film
};

// `jpeg` (a whole JPEG file) with an APP1 Exif segment after its start marker. InputError when the
// bytes are not a JPEG.
std::string with_exif(const std::string& jpeg, const CameraExif& exif);

}  // namespace nf::io
