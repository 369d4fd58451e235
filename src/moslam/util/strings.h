// Strict text parsing. std::stod accepts "1.5abc" and throws on failure; readers of data sets need
// a parser that rejects trailing garbage and reports failure as a value so they can name the line.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace moslam {

std::string_view Trim(std::string_view s);
// Splits on spaces, tabs and (when `commas` is true) commas; empty fields are dropped.
std::vector<std::string_view> SplitFields(std::string_view s, bool commas = false);
// The whole of `s` must be a number ("nan" and "inf" are accepted and returned as such).
std::optional<double> ParseDouble(std::string_view s);
std::optional<long long> ParseInt(std::string_view s);
bool StartsWith(std::string_view s, std::string_view prefix);
bool EndsWith(std::string_view s, std::string_view suffix);
std::string ToLower(std::string_view s);
// `s` for an error message: whole when it has at most `max_chars` characters, else its first
// `max_chars` followed by "..." (and the full length), so that one bad line of a file, which may
// be megabytes without a newline, cannot make a message megabytes long.
std::string Excerpt(std::string_view s, size_t max_chars = 80);

}  // namespace moslam
