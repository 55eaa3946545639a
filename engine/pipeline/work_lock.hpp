#pragma once
// One run per WORK folder. Two runs on the same WORK (a batch task requeued while its first copy
// still runs on another node, or a user starting a second terminal) would each swap stage folders
// under the other. WORK/.lock names its holder (host, pid, start, command); the holder refreshes
// the file's time every kHeartbeat so another host can tell a live holder from a dead one.
// A lock is stale, and taken over with a warning, when its process is gone (same host) or its file
// has not been refreshed for NF_WORK_LOCK_STALE_S seconds (default 300; another host, whose pids
// mean nothing here). Created with O_EXCL, which NFS v3 and later honour.
#include <condition_variable>
#include <filesystem>
#include <mutex>
#include <string>
#include <thread>

#include "engine/core/json.hpp"

namespace nf::pipeline {

class WorkLock {
 public:
  // Takes WORK/.lock (creating WORK) or throws InputError naming the holder and what to do.
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
