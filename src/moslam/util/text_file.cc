#include "moslam/util/text_file.h"

#include <filesystem>
#include <fstream>

#include "moslam/util/error.h"
#include "moslam/util/strings.h"

namespace moslam {

std::vector<TextLine> ReadDataLines(const std::string& path) {
  RequireFile(path, "text file");
  std::ifstream in(path);
  if (!in) ThrowInFile(path, "cannot be opened for reading");
  std::vector<TextLine> lines;
  std::string raw;
  int number = 0;
  while (std::getline(in, raw)) {
    ++number;
    const std::string_view text = Trim(raw);
    if (text.empty() || text.front() == '#') continue;
    lines.push_back({number, std::string(text)});
  }
  if (in.bad()) ThrowInFile(path, "read error");
  return lines;
}

void RequireFile(const std::string& path, const std::string& what) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    ThrowInFile(path, fmt::format("is a directory, not a {}", what));
  }
  if (!std::filesystem::is_regular_file(path, ec)) {
    ThrowInFile(path, fmt::format("{} not found (or not a regular file)", what));
  }
}

void RequireDirectory(const std::string& path, const std::string& what) {
  std::error_code ec;
  if (!std::filesystem::is_directory(path, ec)) {
    ThrowInFile(path, fmt::format("{} not found (or not a directory)", what));
  }
}

}  // namespace moslam
