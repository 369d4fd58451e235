#include "moslam/util/strings.h"

#include <cctype>
#include <cerrno>
#include <cstdlib>

#include <fmt/format.h>

namespace moslam {

std::string_view Trim(std::string_view s) {
  const char* kSpace = " \t\r\n\v\f";
  const size_t begin = s.find_first_not_of(kSpace);
  if (begin == std::string_view::npos) return {};
  const size_t end = s.find_last_not_of(kSpace);
  return s.substr(begin, end - begin + 1);
}

std::vector<std::string_view> SplitFields(std::string_view s, bool commas) {
  std::vector<std::string_view> fields;
  size_t i = 0;
  auto is_sep = [commas](char c) {
    return c == ' ' || c == '\t' || c == '\r' || c == '\n' || (commas && c == ',');
  };
  while (i < s.size()) {
    while (i < s.size() && is_sep(s[i])) ++i;
    const size_t begin = i;
    while (i < s.size() && !is_sep(s[i])) ++i;
    if (i > begin) fields.push_back(s.substr(begin, i - begin));
  }
  return fields;
}

std::optional<double> ParseDouble(std::string_view s) {
  s = Trim(s);
  if (s.empty()) return std::nullopt;
  // strtod needs a terminated string; fields are short, so the copy is cheap.
  const std::string copy(s);
  char* end = nullptr;
  errno = 0;
  const double value = std::strtod(copy.c_str(), &end);
  if (end != copy.c_str() + copy.size()) return std::nullopt;
  if (errno == ERANGE && value != 0.0) return std::nullopt;  // overflow; underflow is fine
  return value;
}

std::optional<long long> ParseInt(std::string_view s) {
  s = Trim(s);
  if (s.empty()) return std::nullopt;
  const std::string copy(s);
  char* end = nullptr;
  errno = 0;
  const long long value = std::strtoll(copy.c_str(), &end, 10);
  if (end != copy.c_str() + copy.size() || errno == ERANGE) return std::nullopt;
  return value;
}

bool StartsWith(std::string_view s, std::string_view prefix) {
  return s.substr(0, prefix.size()) == prefix;
}

bool EndsWith(std::string_view s, std::string_view suffix) {
  return s.size() >= suffix.size() && s.substr(s.size() - suffix.size()) == suffix;
}

std::string ToLower(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

std::string Excerpt(std::string_view s, size_t max_chars) {
  if (s.size() <= max_chars) return std::string(s);
  return fmt::format("{}... ({} characters)", s.substr(0, max_chars), s.size());
}

}  // namespace moslam
