// Shared pieces of the data-set readers: parsing index-file fields with errors that name the file
// and line, resolving the image paths they list, and the ordering rule for timestamps.
// Used by the readers in this module; not part of the data-set API.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "moslam/util/text_file.h"

namespace moslam::io::internal {

// The line's fields (split on blanks, and on commas when `commas`); throws InputError at the
// line unless there are exactly `count`. `format` describes the expected line in the message.
std::vector<std::string_view> SplitExactly(const std::string& path, const TextLine& line,
                                           size_t count, bool commas, const char* format);

// A finite number of seconds; throws InputError at the line otherwise (garbage, NaN, inf).
double ParseSeconds(const std::string& path, const TextLine& line, std::string_view field);

// Throws InputError at the line unless `current` > `previous` (when there is a previous stamp):
// a SLAM system needs frames in time order, and a repeated stamp is a corrupted index.
void RequireIncreasing(const std::string& path, const TextLine& line,
                       std::optional<double> previous, double current);

// `relative` resolved against `root` (absolute paths are kept as they are).
std::string ResolvePath(const std::string& root, std::string_view relative);

// Throws InputError at the index file's line unless `image` (listed there) exists.
void RequireListedFile(const std::string& index_path, int line, const std::string& image);

// `parent`/`child`, or nullopt when that is not an existing regular file.
std::optional<std::string> ExistingFile(const std::string& parent, const std::string& child);

// The last component of a folder path, ignoring trailing slashes ("a/b/" -> "b").
std::string FolderName(const std::string& path);

}  // namespace moslam::io::internal
