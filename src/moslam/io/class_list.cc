#include "moslam/io/class_list.h"

#include <set>

#include <fmt/format.h>

#include "moslam/util/error.h"
#include "moslam/util/strings.h"
#include "moslam/util/text_file.h"

namespace moslam::io {

std::vector<ClassInfo> ReadClassList(const std::string& path) {
  RequireFile(path, "class list");
  std::vector<ClassInfo> classes;
  std::set<int> ids;
  std::set<std::string> names;
  for (const TextLine& line : ReadDataLines(path)) {
    const auto fields = SplitFields(line.text);
    const auto id = fields.size() == 3 ? ParseInt(fields[0]) : std::nullopt;
    const auto movable = fields.size() == 3 ? ParseInt(fields[2]) : std::nullopt;
    if (!id || !movable || (*movable != 0 && *movable != 1)) {
      ThrowAtLine(path, line.number,
                  "expected `<id> <name> <movable 0|1>`, got '" + Excerpt(line.text) + "'");
    }
    if (*id < 0 || *id > 255) ThrowAtLine(path, line.number, "class id must be in 0..255");
    ClassInfo info{static_cast<int>(*id), std::string(fields[1]), *movable == 1, line.number};
    if (!ids.insert(info.id).second) {
      ThrowAtLine(path, line.number, fmt::format("class id {} repeated", info.id));
    }
    if (!names.insert(info.name).second) {
      ThrowAtLine(path, line.number, "class name '" + Excerpt(info.name) + "' repeated");
    }
    classes.push_back(std::move(info));
  }
  if (classes.empty()) ThrowInFile(path, "lists no classes");
  return classes;
}

}  // namespace moslam::io
