// Test support: a full disk without a full disk. Lowers this process's file-size limit
// (RLIMIT_FSIZE) while the object lives: a write past it fails with EFBIG, through the same
// code paths as a write to a full disk (ENOSPC). SIGXFSZ, whose default action would end the
// process, is ignored meanwhile, as `moslam` ignores it.
#pragma once

#include <sys/resource.h>

#include <csignal>

namespace moslam::testing {

class FileSizeLimit {
 public:
  explicit FileSizeLimit(rlim_t bytes) {
    getrlimit(RLIMIT_FSIZE, &saved_);
    old_handler_ = std::signal(SIGXFSZ, SIG_IGN);
    rlimit limit = saved_;
    limit.rlim_cur = bytes;
    setrlimit(RLIMIT_FSIZE, &limit);
  }
  ~FileSizeLimit() {
    setrlimit(RLIMIT_FSIZE, &saved_);
    std::signal(SIGXFSZ, old_handler_);
  }
  FileSizeLimit(const FileSizeLimit&) = delete;
  FileSizeLimit& operator=(const FileSizeLimit&) = delete;

 private:
  rlimit saved_{};
  void (*old_handler_)(int) = nullptr;
};

}  // namespace moslam::testing
