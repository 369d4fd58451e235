#include "moslam/util/atomic_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

#include <fmt/format.h>

#include "moslam/util/error.h"

namespace moslam {
namespace {

// The reason of the last failed system call, as strerror gives it.
std::string Reason(int error) { return std::strerror(error); }

// write(2) until everything is written; false (errno set) on the first failure.
bool WriteAll(int fd, std::string_view contents) {
  size_t done = 0;
  while (done < contents.size()) {
    const ssize_t n = ::write(fd, contents.data() + done, contents.size() - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      return false;
    }
    done += static_cast<size_t>(n);
  }
  return true;
}

}  // namespace

std::string TemporaryPathFor(const std::string& path) {
  return fmt::format("{}.tmp{}", path, ::getpid());
}

void WriteFileAtomically(const std::string& path, std::string_view contents,
                         const std::string& what) {
  const std::string temp = TemporaryPathFor(path);
  const int fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) {
    ThrowInFile(
        path, fmt::format("cannot write the {}: cannot create {}: {}", what, temp, Reason(errno)));
  }
  // fsync before the rename: after a power cut the new name must not point at blocks that
  // were never written.
  bool ok = WriteAll(fd, contents) && ::fsync(fd) == 0;
  int error = ok ? 0 : errno;
  if (::close(fd) != 0 && ok) {
    ok = false;
    error = errno;
  }
  if (ok && std::rename(temp.c_str(), path.c_str()) != 0) {
    ok = false;
    error = errno;
  }
  if (!ok) {
    ::unlink(temp.c_str());
    ThrowInFile(path, fmt::format("cannot write the {} ({} bytes): {}; the file was left as it was",
                                  what, contents.size(), Reason(error)));
  }
}

}  // namespace moslam
