#pragma once
// Atomic file writes: write to a temporary name beside the target, then rename, so a crash never
// leaves a partial file and readers see either the old or the new content.
#include <filesystem>
#include <functional>
#include <ostream>
#include <string_view>
#include <vector>

namespace nf {

// Calls `write` with a stream on a temporary file in the target's folder, then renames it over
// `path`. Throws InputError naming the path if it cannot be written; the temporary is removed.
void write_file_atomic(const std::filesystem::path& path, const std::function<void(std::ostream&)>& write);
void write_file_atomic(const std::filesystem::path& path, std::string_view content);

// Removes the temporaries that killed runs left in `dir` (the names write_file_atomic gives them,
// whose process no longer exists) and returns their names.
std::vector<std::string> remove_stale_temporaries(const std::filesystem::path& dir);

}  // namespace nf
