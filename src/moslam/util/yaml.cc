#include "moslam/util/yaml.h"

#include <cmath>
#include <fstream>
#include <limits>
#include <optional>

#include <opencv2/core.hpp>

#include "moslam/util/error.h"
#include "moslam/util/strings.h"
#include "moslam/util/text_file.h"

namespace moslam {

struct YamlFile::Impl {
  cv::FileStorage storage;
  std::map<std::string, cv::FileNode> leaves;  // full dotted key -> node
};

namespace {

// OpenCV stores matrices as maps {rows, cols, dt, data}; they are one value, not four keys.
bool IsOpenCvMatrix(const cv::FileNode& node) {
  return node.isMap() && !node["rows"].empty() && !node["cols"].empty() && !node["data"].empty();
}

void Flatten(const cv::FileNode& node, const std::string& prefix,
             std::map<std::string, cv::FileNode>* leaves) {
  for (auto it = node.begin(); it != node.end(); ++it) {
    const cv::FileNode child = *it;
    const std::string key = prefix.empty() ? child.name() : prefix + "." + child.name();
    if (child.isMap() && !IsOpenCvMatrix(child)) {
      Flatten(child, key, leaves);
    } else {
      (*leaves)[key] = child;
    }
  }
}

// Whether `token` is a number OpenCV reads with strtol's base 0: hexadecimal (0x1f) or octal
// (017, read as 15), never what a user who writes them into a settings file means.
bool IsNonDecimalNumber(std::string_view token) {
  if (!token.empty() && (token[0] == '+' || token[0] == '-')) token.remove_prefix(1);
  if (token.size() < 2 || token[0] != '0') return false;
  const char c = token[1];
  return c == 'x' || c == 'X' || (c >= '0' && c <= '9');
}

// Calls `visit(line, key, token)` for every unquoted, uncommented token of the file (split at
// YAML's punctuation), with the key of the token's line ("" when the line has none).
template <typename Visit>
void ForEachPlainToken(const std::string& path, Visit visit) {
  for (const TextLine& line : ReadDataLines(path)) {
    const std::string& text = line.text;
    const size_t colon = text.find(':');
    const std::string key =
        colon == std::string::npos ? std::string() : std::string(Trim(text.substr(0, colon)));
    size_t i = 0;
    while (i < text.size()) {
      const char c = text[i];
      if (c == '#' && (i == 0 || text[i - 1] == ' ' || text[i - 1] == '\t')) break;  // comment
      if (c == '"' || c == '\'') {  // a quoted string is text, whatever it holds
        const size_t close = text.find(c, i + 1);
        if (close == std::string::npos) break;
        i = close + 1;
        continue;
      }
      const size_t end = text.find_first_of(" \t,[]{}:#\"'", i);
      const size_t stop = end == std::string::npos ? text.size() : end;
      if (stop == i) {
        ++i;
        continue;
      }
      visit(line, key, std::string_view(text.data() + i, stop - i));
      i = stop;
    }
  }
}

std::string KeyPrefix(const std::string& key) {
  return key.empty() ? std::string() : fmt::format("key '{}': ", Excerpt(key));
}

// Throws InputError at the first unquoted hexadecimal or octal number, naming the line's key.
void RejectNonDecimalNumbers(const std::string& path) {
  ForEachPlainToken(
      path, [&](const TextLine& line, const std::string& key, std::string_view token) {
        if (!IsNonDecimalNumber(token)) return;
        ThrowAtLine(path, line.number,
                    fmt::format("{}'{}' is not a decimal number (hexadecimal and octal numbers are "
                                "not accepted; write it in decimal)",
                                KeyPrefix(key), Excerpt(token)));
      });
}

// Throws InputError at the first YAML tag other than !!opencv-matrix. Options are numbers,
// strings, lists and OpenCV matrices; a tag only changes how OpenCV reads a value, and OpenCV
// 4.6 loops forever on some "!!binary" values (a base64 block whose header names no element
// type, e.g. "AAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAA"), so this runs before OpenCV sees the file.
void RejectTags(const std::string& path) {
  ForEachPlainToken(
      path, [&](const TextLine& line, const std::string& key, std::string_view token) {
        if (token[0] != '!' || token == "!!opencv-matrix") return;
        ThrowAtLine(path, line.number,
                    fmt::format("{}the YAML tag '{}' is not supported (only !!opencv-matrix is; "
                                "write the value as a number, a string or a list)",
                                KeyPrefix(key), Excerpt(token)));
      });
}

// The key and value of a "key: value" or "key:" line, when the line is one.
struct KeyLine {
  std::string key;
  std::string_view value;  // "" for "key:"
};

std::optional<KeyLine> SplitKeyLine(std::string_view text) {
  const size_t colon = text.find(": ");
  if (colon != std::string_view::npos) {
    return KeyLine{std::string(Trim(text.substr(0, colon))), Trim(text.substr(colon + 2))};
  }
  if (text.size() > 1 && text.back() == ':') {
    return KeyLine{std::string(text.substr(0, text.size() - 1)), {}};
  }
  return std::nullopt;
}

// Whether `value` is one whole quoted string or flow collection: "...", '...', [...], {...}
// with its brackets balanced (quotes inside a collection are not looked into).
bool ClosesOnItsLine(std::string_view value) {
  if (value.size() < 2) return false;
  const char first = value.front();
  const char last = value.back();
  if (first == '"' || first == '\'') return last == first;
  if (!((first == '[' && last == ']') || (first == '{' && last == '}'))) return false;
  int depth = 0;
  for (const char c : value) {
    depth += (c == '[' || c == '{') - (c == ']' || c == '}');
    if (depth < 0) return false;
  }
  return depth == 0;
}

// Throws InputError at a key whose block structure OpenCV refuses as "Incorrect indentation" at
// the line after, away from the key the user has to fix: a "key:" with no block indented below
// it (YAML's null, or a list at the key's own indentation), and a "key: value" with a plain
// value and a block indented below it as well (a matrix's value replaced by a number).
void RejectBadBlocks(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string raw;
  int number = 0;
  int open_line = 0;  // the last key line, while its block (or lack of one) is undecided
  bool needs_block = false;
  size_t open_indent = 0;
  std::string open_key;
  auto next = [&](size_t indent) {
    if (open_line > 0 && needs_block == (indent <= open_indent)) {
      ThrowAtLine(path, open_line,
                  needs_block ? fmt::format("key '{}' has no value (nor a block indented below it)",
                                            Excerpt(open_key))
                              : fmt::format("key '{}' has a value and a block indented below it",
                                            Excerpt(open_key)));
    }
    open_line = 0;
  };
  while (std::getline(in, raw)) {
    ++number;
    const size_t indent = raw.find_first_not_of(" \t\r");
    if (indent == std::string::npos || raw[indent] == '#' || raw[indent] == '%') continue;
    const std::string_view text = Trim(std::string_view(raw).substr(indent));
    next(indent);
    const std::optional<KeyLine> line = SplitKeyLine(text);
    // Values in brackets or quotes may go on over several lines (unless they close on this one);
    // tags open a block.
    if (!line || line->key.find_first_of("\"'{[") != std::string::npos ||
        (!ClosesOnItsLine(line->value) &&
         line->value.find_first_of("\"'{[!|>&*#") != std::string_view::npos)) {
      continue;
    }
    open_line = number;
    open_indent = indent;
    open_key = line->key;
    needs_block = line->value.empty();
  }
  next(0);
}

// OpenCV's parser puts "<file>(<line>): <reason>" into cv::Exception::func and the name of its
// parsing function into err: the line and the reason are what a user can act on.
[[noreturn]] void ThrowParseError(const std::string& path, const cv::Exception& e) {
  const size_t close = e.func.rfind("): ");
  const size_t open = close == std::string::npos ? close : e.func.rfind('(', close);
  if (open != std::string::npos) {
    const std::optional<long long> line = ParseInt(e.func.substr(open + 1, close - open - 1));
    if (line && *line > 0 && *line <= std::numeric_limits<int>::max()) {
      ThrowAtLine(path, static_cast<int>(*line),
                  fmt::format("is not valid YAML: {}", Excerpt(e.func.substr(close + 3))));
    }
  }
  ThrowInFile(path, fmt::format("is not valid YAML: {}", Excerpt(e.err)));
}

[[noreturn]] void WrongType(const std::string& path, const std::string& key, const char* expected) {
  ThrowInFile(path, fmt::format("key '{}' must be {}", Excerpt(key), expected));
}

}  // namespace

YamlFile::YamlFile(const std::string& path) : path_(path), impl_(std::make_unique<Impl>()) {
  RequireFile(path, "YAML options file");
  RejectTags(path);
  RejectBadBlocks(path);
  // OpenCV's parser reports some malformed input with other exceptions than cv::Exception
  // (std::length_error from a string it sizes from garbage): all of them are bad input here.
  try {
    impl_->storage.open(path, cv::FileStorage::READ | cv::FileStorage::FORMAT_YAML);
  } catch (const cv::Exception& e) {
    ThrowParseError(path, e);
  } catch (const std::exception& e) {
    ThrowInFile(path, fmt::format("is not valid YAML ({})", Excerpt(e.what())));
  }
  if (!impl_->storage.isOpened()) ThrowInFile(path, "cannot be parsed as YAML");
  // After the parse, so that a binary file is reported as not YAML rather than quoted.
  RejectNonDecimalNumbers(path);
  const cv::FileNode root = impl_->storage.root();
  // Options are named keys; a list (or a lone scalar) at the top has no key to name, and
  // iterating it as a map trips an assertion inside OpenCV.
  if (!root.isMap() && !root.isNone()) {
    ThrowInFile(path, "the top level must be a map of 'key: value' lines, not a list or a value");
  }
  try {
    Flatten(root, "", &impl_->leaves);
  } catch (const std::exception& e) {
    ThrowInFile(path, fmt::format("cannot be read as options: {}", Excerpt(e.what())));
  }
}

YamlFile::~YamlFile() = default;
YamlFile::YamlFile(YamlFile&&) noexcept = default;
YamlFile& YamlFile::operator=(YamlFile&&) noexcept = default;

bool YamlFile::Has(const std::string& key) const { return impl_->leaves.count(key) > 0; }

std::vector<std::string> YamlFile::Keys() const {
  std::vector<std::string> keys;
  for (const auto& [key, node] : impl_->leaves) keys.push_back(key);
  return keys;
}

template <>
bool YamlFile::Read<double>(const std::string& key, double* value) {
  const auto it = impl_->leaves.find(key);
  if (it == impl_->leaves.end()) return false;
  read_.insert(key);
  const cv::FileNode& node = it->second;
  if (node.isInt()) {
    *value = static_cast<int>(node);
  } else if (node.isReal()) {
    *value = node.real();
  } else if (node.isString()) {
    // OpenCV's YAML reader keeps ".nan"/"nan"-like scalars as strings; reject them explicitly.
    const auto parsed = ParseDouble(node.string());
    if (!parsed) WrongType(path_, key, "a number");
    *value = *parsed;
  } else {
    WrongType(path_, key, "a number");
  }
  if (!std::isfinite(*value)) WrongType(path_, key, "a finite number");
  return true;
}

template <>
bool YamlFile::Read<float>(const std::string& key, float* value) {
  double v = 0.0;
  if (!Read<double>(key, &v)) return false;
  *value = static_cast<float>(v);
  return true;
}

template <>
bool YamlFile::Read<int>(const std::string& key, int* value) {
  const auto it = impl_->leaves.find(key);
  if (it == impl_->leaves.end()) return false;
  read_.insert(key);
  if (!it->second.isInt()) WrongType(path_, key, "an integer");
  *value = static_cast<int>(it->second);
  return true;
}

template <>
bool YamlFile::Read<bool>(const std::string& key, bool* value) {
  const auto it = impl_->leaves.find(key);
  if (it == impl_->leaves.end()) return false;
  read_.insert(key);
  const cv::FileNode& node = it->second;
  if (node.isInt()) {
    const int v = static_cast<int>(node);
    if (v != 0 && v != 1) WrongType(path_, key, "0 or 1 (or true/false)");
    *value = v == 1;
  } else if (node.isString()) {
    const std::string s = ToLower(node.string());
    if (s == "true") {
      *value = true;
    } else if (s == "false") {
      *value = false;
    } else {
      WrongType(path_, key, "0 or 1 (or true/false)");
    }
  } else {
    WrongType(path_, key, "0 or 1 (or true/false)");
  }
  return true;
}

template <>
bool YamlFile::Read<std::string>(const std::string& key, std::string* value) {
  const auto it = impl_->leaves.find(key);
  if (it == impl_->leaves.end()) return false;
  read_.insert(key);
  if (!it->second.isString()) WrongType(path_, key, "a string");
  *value = it->second.string();
  return true;
}

template <>
bool YamlFile::Read<std::vector<double>>(const std::string& key, std::vector<double>* value) {
  const auto it = impl_->leaves.find(key);
  if (it == impl_->leaves.end()) return false;
  read_.insert(key);
  cv::FileNode node = it->second;
  if (IsOpenCvMatrix(node)) node = node["data"];
  if (!node.isSeq()) WrongType(path_, key, "a list of numbers");
  value->clear();
  for (auto e = node.begin(); e != node.end(); ++e) {
    if (!(*e).isReal() && !(*e).isInt()) WrongType(path_, key, "a list of numbers");
    value->push_back((*e).isInt() ? static_cast<double>(static_cast<int>(*e)) : (*e).real());
  }
  return true;
}

template <>
bool YamlFile::Read<std::vector<std::string>>(const std::string& key,
                                              std::vector<std::string>* value) {
  const auto it = impl_->leaves.find(key);
  if (it == impl_->leaves.end()) return false;
  read_.insert(key);
  const cv::FileNode& node = it->second;
  if (!node.isSeq()) WrongType(path_, key, "a list of strings");
  value->clear();
  for (auto e = node.begin(); e != node.end(); ++e) {
    if (!(*e).isString()) WrongType(path_, key, "a list of strings");
    value->push_back((*e).string());
  }
  return true;
}

template <typename T>
T YamlFile::Required(const std::string& key) {
  T value{};
  if (!Read(key, &value)) ThrowInFile(path_, fmt::format("required key '{}' is missing", key));
  return value;
}

template double YamlFile::Required<double>(const std::string&);
template float YamlFile::Required<float>(const std::string&);
template int YamlFile::Required<int>(const std::string&);
template bool YamlFile::Required<bool>(const std::string&);
template std::string YamlFile::Required<std::string>(const std::string&);
template std::vector<double> YamlFile::Required<std::vector<double>>(const std::string&);
template std::vector<std::string> YamlFile::Required<std::vector<std::string>>(const std::string&);

void YamlFile::IgnorePrefix(const std::string& prefix) { ignored_prefixes_.push_back(prefix); }

void YamlFile::RejectUnread() const {
  for (const auto& [key, node] : impl_->leaves) {
    if (read_.count(key)) continue;
    bool ignored = false;
    for (const std::string& prefix : ignored_prefixes_) ignored |= StartsWith(key, prefix);
    if (!ignored) ThrowInFile(path_, fmt::format("unknown key '{}' (misspelt?)", Excerpt(key)));
  }
}

}  // namespace moslam
