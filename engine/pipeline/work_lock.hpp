#pragma once
// One run per WORK folder. Two runs on the same WORK (a batch task requeued while its first copy
// still runs on another node, or a user starting a second terminal) would each swap stage folders
// under the other. WORK/.lock names its holder (host, pid, start, command); the holder refreshes
// the file's time every tenth of the stale limit (at most 30 s) so another host can tell a live
// holder from a dead one, and checks that the lock is still its own: a holder whose lock was taken
// (it was suspended past the limit) stops its run as Ctrl-C would, saving its checkpoint.
// A lock is stale, and taken over with a warning, when its process is gone (same host) or its file
// has not been refreshed for NF_WORK_LOCK_STALE_S seconds (default 300; another host, whose pids
// mean nothing here; the two hosts' clocks must agree to well within that). Created with O_EXCL,
// which NFS v3 and later honour; taken over by renaming the stale file aside first, so of two
// takers only the one that renamed what it judged goes on.
#include <condition_variable>
#include <filesystem>
#include <mutex>
#include <string>
#include <thread>

#include "engine/core/error.hpp"
#include "engine/core/json.hpp"

namespace nf::pipeline {

// The WORK folder is in use by a live run: a later attempt may succeed (a batch task requeues).
class WorkBusyError : public InputError {
 public:
  explicit WorkBusyError(const std::string& message) : InputError(message) {}
};

class WorkLock {
 public:
  // Takes WORK/.lock (creating WORK) or throws WorkBusyError naming the holder and what to do
  // (InputError for a file there that nf_gpu did not write).
  WorkLock(const std::filesystem::path& work, const std::string& command);
  ~WorkLock();  // stops the heartbeat and removes the file when it is still ours
  WorkLock(const WorkLock&) = delete;
  WorkLock& operator=(const WorkLock&) = delete;

  static std::filesystem::path file(const std::filesystem::path& work) { return work / ".lock"; }
  // The holder's record ({"host","pid","started","command"}), or null when unlocked or unreadable.
  static json holder(const std::filesystem::path& work);
  // Why a held lock is stale ("" when its holder may be alive).
  static std::string stale_reason(const std::filesystem::path& work, const json& holder);

 private:
  void heartbeat();
  std::filesystem::path path_;
  std::string token_;  // our record as written: the file is removed only while it still holds it
  std::mutex mutex_;
  std::condition_variable wake_;
  bool stopping_ = false;
  std::thread thread_;
};

}  // namespace nf::pipeline
