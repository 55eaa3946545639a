#include "engine/pipeline/export_page.hpp"

#include <sstream>

#include "engine/core/text.hpp"

namespace nf::pipeline {
namespace {

// What opens each groom or body file (README, "Using the result").
std::string opened_by(const std::string& file) {
  if (file == "fur.usda") return "Houdini, Unreal, Omniverse (USD)";
  if (file == "fur.hair") return "Blender through tools/blender/nf_gpu_import.py (hair curves with their colours)";
  if (file == "fur.ply") return "Blender, MeshLab (vertex chains, vertex colours)";
  if (file == "fur.obj") return "most tools (polylines)";
  if (file == "body.glb") return "Blender, Unreal, Houdini (glTF with its skeleton)";
  if (file == "roots.npz") return "numpy (each strand's face and barycentric coordinates on body.glb)";
  return "";
}

std::string size_text(double bytes) {
  std::ostringstream s;
  s.precision(bytes >= 1e7 ? 0 : 1);
  s << std::fixed;
  if (bytes >= 1e6) s << bytes / 1e6 << " MB";
  else s << bytes / 1e3 << " kB";
  return s.str();
}

}  // namespace

std::string export_page_html(const ExportPage& p) {
  std::ostringstream s;
  s << "<!doctype html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>" << html_escape(p.title) << "</title>\n"
    << "<style>body{font-family:sans-serif;margin:2em;background:#fafafa;color:#222}h1{font-weight:600}"
       "table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #ccc;padding:4px 10px;text-align:left}"
       ".turntable img{width:24%;min-width:160px;margin:2px;background:#fff}.compare img{width:100%;max-width:960px;margin:4px 0;display:block}"
       "</style></head>\n<body data-images-loaded=\"0\">\n<h1>" << html_escape(p.title) << "</h1>\n";
  if (!p.turntable.empty()) {
    s << "<h2>Around the animal</h2>\n<div class=\"turntable\">\n";
    for (const std::string& f : p.turntable) s << "<img src=\"" << html_escape(f) << "\" alt=\"" << html_escape(f) << "\">\n";
    s << "</div>\n";
  }
  if (!p.compare.empty()) {
    s << "<h2>Beside photos the fur was not trained on (its colours come from every photo)</h2>\n<div class=\"compare\">\n";
    for (const std::string& f : p.compare) s << "<img src=\"" << html_escape(f) << "\" alt=\"" << html_escape(f) << "\">\n";
    s << "</div>\n";
  }
  if (!p.figures.empty()) {
    s << "<h2>What was measured</h2>\n<table>\n";
    for (const auto& [what, value] : p.figures) s << "<tr><th>" << html_escape(what) << "</th><td>" << html_escape(value) << "</td></tr>\n";
    s << "</table>\n";
  }
  s << "<h2>Files</h2>\n<table><tr><th>file</th><th>size</th><th>opens in</th></tr>\n";
  for (const json& f : p.files) {
    const std::string name = f.value("file", "");
    s << "<tr><td><a href=\"" << html_escape(name) << "\">" << html_escape(name) << "</a></td><td>" << size_text(f.value("bytes", 0.0))
      << "</td><td>" << html_escape(opened_by(name)) << "</td></tr>\n";
  }
  s << "</table>\n<p>Metres, +y up, the animal facing +z. export.json holds the map back to the photos' frame.</p>\n"
    << "<script>window.addEventListener('load',function(){var n=0;for(var i of document.images)if(i.complete&&i.naturalWidth>0)n++;"
       "document.body.dataset.imagesLoaded=n;});</script>\n</body></html>\n";
  return s.str();
}

}  // namespace nf::pipeline
