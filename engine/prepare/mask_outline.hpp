#pragma once
// A segmentation's outline moved onto the photo's own edges. GrabCut's smoothness term cuts a
// pixel or two off the true outline, inwards across a tuft and outwards across a gap (on a synth
// dog at 320 px, 84 % of the automatic masks' wrong pixels lay within two of the true outline,
// about as many on either side). A guided filter (He, Sun and Tang 2010) fits the mask, window by
// window, as a linear function of the photo's colour: where the animal's colours differ from the
// background's beside it, the filtered mask follows the colour edge, and thresholded at one half
// it is a mask again. Where a window's colours do not tell the two sides apart the cut stands.
// Only pixels near the cut's outline may change: the filter's windows reach further, and a patch
// of the animal that shares the background's colours away from its outline stays as cut.
#include <opencv2/core.hpp>

namespace nf::prepare {

struct OutlineOptions {
  int radius = 0;        // the filter's window half-width in pixels; 0: 2.5 % of the photo's longer side (8 px at 320)
  double epsilon = 3e-5;  // regularisation, in (colour / 255)^2: how faint a colour edge the mask may follow
  int band = 0;          // pixels either side of the cut's outline that may change; 0: 1 % of the longer side, at least 3
  // The least separation of the two sides' colours (their means' squared distance over their summed
  // variances, averaged over the windows) where the outline follows the filter: 0.46 is the median
  // along the automatic masks' outlines on a synth dog at 320 px (1.2 on a cat at 512), 0 where one
  // flat colour leaves nothing to follow.
  double min_separation = 0.1;
};

// `photo`: 8-bit BGR; `mask`: 8-bit, non-zero = animal, the photo's size. Returns the refined mask
// (0 or 255). An empty or full mask is returned as it is.
cv::Mat snap_outline_to_photo(const cv::Mat& photo, const cv::Mat& mask, const OutlineOptions& options = {});

}  // namespace nf::prepare
