#pragma once
// The export folder's index.html: what a person opens first. The previews (the turntable and the
// groom beside held-out photos, in the strands' colours), the figures the reconstruction measured,
// and the files with their sizes and what opens them. Self-contained: relative links to the
// folder's own files, no script but one that marks, once the page has loaded, how many of its
// images did load (`data-images-loaded` on <body>, what the page test reads).
#include <string>
#include <utility>
#include <vector>

#include "engine/core/json.hpp"

namespace nf::pipeline {

struct ExportPage {
  std::string title;                                         // e.g. "nf_gpu groom: cat"
  std::vector<std::pair<std::string, std::string>> figures;  // (what, value as text), in order
  json files = json::array();                                // export.json's {"file", "bytes"} rows
  std::vector<std::string> turntable;                        // image files, in order
  std::vector<std::string> compare;                          // image files (photo | render)
};

std::string export_page_html(const ExportPage& page);

}  // namespace nf::pipeline
