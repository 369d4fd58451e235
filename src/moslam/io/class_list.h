// The class list of a synthetic sequence or training folder (`classes.txt`, written by
// `moslam synth`, docs/SYNTH.md): one `<id> <name> <movable 0|1>` line per class, `#` comments.
// Read by the synthetic ground-truth mask source (runner/) and the weak pipeline's data (weak/).
#pragma once

#include <string>
#include <vector>

namespace moslam::io {

struct ClassInfo {
  int id = 0;  // 0..255, the pixel value in class/<stem>.png
  std::string name;
  bool movable = false;
  int line = 0;  // line of the file it came from (for messages about it)
};

// Reads a class list in file order; InputError naming file and line for a malformed line, an id
// outside 0..255, or a repeated id or name, and naming the file when it lists no class.
std::vector<ClassInfo> ReadClassList(const std::string& path);

}  // namespace moslam::io
