#pragma once
// This machine and its processes, as the files shared between hosts name them (temporaries, locks).
#include <sys/types.h>

#include <filesystem>
#include <string>

namespace nf {

// The host name, with '/' and '@' replaced so that it can go into a file name ("localhost" when the
// system will not say).
std::string host_name();

// The time now as "2026-12-05T11:30:00Z" (UTC), for records people and other hosts read.
std::string utc_now();

// Whether a process of this host with this pid exists (a pid of another user's process counts).
bool process_alive(pid_t pid);

// Flushes a written file, then its folder's entry, to the disk (or the file server): what a rename
// needs before it is trusted on a shared filesystem. Returns 0 or the errno of a failure that lost
// data (EIO, ENOSPC, EDQUOT: on NFS the write errors a server defers surface here); a filesystem
// that cannot sync (EINVAL, EROFS, ENOTSUP: tmpfs, some FUSE) counts as success.
int sync_file(const std::filesystem::path& file);
int sync_folder(const std::filesystem::path& folder);
// Every file and folder under `folder`, then the folder itself: before a finished output folder is
// renamed into place (its writers include libraries that do not sync).
int sync_tree(const std::filesystem::path& folder);  // the first failure's errno, or 0

}  // namespace nf
