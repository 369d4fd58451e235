// Files written whole or not at all: the contents go to a temporary file beside the target, which
// is flushed to disk and then renamed over it. A reader (or a user looking at an output folder
// after a crash, a full disk or a kill) sees either the previous file or the complete new one,
// never a file cut short that looks complete (issue 31: faults in the middle of a run).
#pragma once

#include <string>
#include <string_view>

namespace moslam {

// Writes `contents` to `path` atomically (rename(2) within one folder). On any failure (the folder
// missing or read-only, the disk full, the file-size limit) the temporary file is removed, `path`
// is left as it was, and an InputError names `path`, what was being written (`what`, e.g.
// "trajectory") and the system's reason ("No space left on device").
void WriteFileAtomically(const std::string& path, std::string_view contents,
                         const std::string& what);

// The temporary name WriteFileAtomically uses for `path` in this process (for tests).
std::string TemporaryPathFor(const std::string& path);

}  // namespace moslam
