// Line-oriented text files, as used by TUM, KITTI and EuRoC: the lines that carry data, with their
// 1-based line numbers so that readers can name the line of a malformed entry.
#pragma once

#include <string>
#include <vector>

namespace moslam {

struct TextLine {
  int number = 0;    // 1-based line number in the file
  std::string text;  // the line without its end-of-line characters, trimmed
};

// Reads `path`, dropping blank lines and lines whose first non-blank character is '#'.
// Throws InputError naming the file when it cannot be opened.
std::vector<TextLine> ReadDataLines(const std::string& path);

// Throws InputError naming `path` unless it is an existing regular file.
void RequireFile(const std::string& path, const std::string& what);
// Throws InputError naming `path` unless it is an existing directory.
void RequireDirectory(const std::string& path, const std::string& what);

}  // namespace moslam
