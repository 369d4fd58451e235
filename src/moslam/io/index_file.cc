#include "moslam/io/index_file.h"

#include <cmath>
#include <filesystem>

#include <fmt/format.h>

#include "moslam/util/error.h"
#include "moslam/util/strings.h"

namespace moslam::io::internal {

namespace fs = std::filesystem;

std::vector<std::string_view> SplitExactly(const std::string& path, const TextLine& line,
                                           size_t count, bool commas, const char* format) {
  std::vector<std::string_view> fields = SplitFields(line.text, commas);
  if (fields.size() != count) {
    ThrowAtLine(path, line.number,
                fmt::format("expected {} fields ({}), got {}: '{}'", count, format, fields.size(),
                            Excerpt(line.text)));
  }
  return fields;
}

double ParseSeconds(const std::string& path, const TextLine& line, std::string_view field) {
  const std::optional<double> value = ParseDouble(field);
  if (!value)
    ThrowAtLine(path, line.number, fmt::format("timestamp '{}' is not a number", Excerpt(field)));
  if (!std::isfinite(*value)) {
    ThrowAtLine(path, line.number,
                fmt::format("timestamp '{}' is not a finite number", Excerpt(field)));
  }
  return *value;
}

void RequireIncreasing(const std::string& path, const TextLine& line,
                       std::optional<double> previous, double current) {
  if (previous && !(current > *previous)) {
    ThrowAtLine(path, line.number,
                fmt::format("timestamp {:.9f} does not increase (previous entry: {:.9f}); "
                            "entries must be in strictly increasing time order",
                            current, *previous));
  }
}

std::string ResolvePath(const std::string& root, std::string_view relative) {
  const fs::path p{std::string(relative)};
  if (p.is_absolute()) return p.string();
  return (fs::path(root) / p).string();
}

void RequireListedFile(const std::string& index_path, int line, const std::string& image) {
  std::error_code ec;
  if (!fs::is_regular_file(image, ec)) {
    ThrowAtLine(index_path, line, fmt::format("listed file '{}' not found", Excerpt(image, 400)));
  }
}

std::optional<std::string> ExistingFile(const std::string& parent, const std::string& child) {
  const std::string path = (fs::path(parent) / child).string();
  std::error_code ec;
  if (fs::is_regular_file(path, ec)) return path;
  return std::nullopt;
}

std::string FolderName(const std::string& path) {
  std::error_code ec;
  fs::path p = fs::absolute(path, ec).lexically_normal();  // "." and "a/b/" name their folder
  if (ec) p = fs::path(path);
  while (!p.empty() && p.filename().empty() && p.has_parent_path() && p != p.root_path()) {
    p = p.parent_path();
  }
  return p.filename().string();
}

}  // namespace moslam::io::internal
