#pragma once
// Resuming a stage from its checkpoint: load it when it exists; one that does not fit (made by
// another version or configuration, or unreadable) is deleted with a note and the stage starts
// afresh, so a stale checkpoint never stops a run.
#include <filesystem>
#include <functional>
#include <string>

namespace nf::pipeline {

// `load` returns true when it restored the state, false when the file belongs to other settings
// (it may also throw InputError). `reset` puts the half-loaded state back to a fresh start.
// Returns whether the stage resumed.
bool resume_or_discard(const std::string& stage, const std::filesystem::path& checkpoint,
                       const std::function<bool()>& load, const std::function<void()>& reset);

}  // namespace nf::pipeline
