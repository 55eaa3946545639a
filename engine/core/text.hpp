#pragma once
// Small text helpers for messages people read.
#include <string>
#include <string_view>
#include <vector>

namespace nf {

// Levenshtein distance (insertions, deletions, substitutions; bytes).
std::size_t edit_distance(std::string_view a, std::string_view b);

// The candidate closest to `word` when it is close enough to be a likely typo (at most a third of
// its length, and at least 2, edits away), else "". Ties go to the earlier candidate.
std::string closest_match(std::string_view word, const std::vector<std::string>& candidates);

// " (did you mean 'x'?)" for closest_match, or "" when nothing is close.
std::string did_you_mean(std::string_view word, const std::vector<std::string>& candidates);

// ASCII letters lower-cased (other bytes, UTF-8 included, unchanged).
std::string to_lower(std::string text);

// Whether `text` is well-formed UTF-8 (no overlong forms, surrogates or code points past U+10FFFF):
// what JSON files and records can hold.
bool is_utf8(std::string_view text);

// Text safe inside HTML elements and quoted attributes (< > & " escaped).
std::string html_escape(std::string_view text);

// At most `max_bytes` of `text` (cut at a UTF-8 character boundary, "..." appended when cut), with
// control characters as spaces: for quoting untrusted text in a message.
std::string shorten(std::string_view text, std::size_t max_bytes);

// A word for a POSIX shell: as it is when it holds only safe characters, else single-quoted (for
// commands printed to be pasted, and job scripts).
std::string shell_quote(std::string_view word);

// "a, b, c"
std::string join(const std::vector<std::string>& items, std::string_view separator = ", ");

}  // namespace nf
