#include "moslam/vocab/shipped_location.h"

#include <system_error>

namespace moslam::vocab {

std::vector<std::filesystem::path> ShippedVocabularyCandidates(const std::filesystem::path& cwd,
                                                               const std::filesystem::path& exe) {
  std::vector<std::filesystem::path> candidates{cwd / kShippedVocabulary};
  if (exe.empty()) return candidates;
  std::filesystem::path folder = exe.parent_path();
  for (int up = 0; up <= 4 && !folder.empty(); ++up) {
    candidates.push_back(folder / kShippedVocabulary);
    if (folder == folder.parent_path()) break;  // the root
    folder = folder.parent_path();
  }
  return candidates;
}

std::filesystem::path FindShippedVocabulary(const std::filesystem::path& cwd,
                                            const std::filesystem::path& exe) {
  for (const std::filesystem::path& candidate : ShippedVocabularyCandidates(cwd, exe)) {
    std::error_code error;
    if (std::filesystem::is_regular_file(candidate, error)) return candidate;
  }
  return {};
}

std::filesystem::path CurrentExecutable() {
  std::error_code error;
  std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", error);
  return error ? std::filesystem::path() : exe;
}

}  // namespace moslam::vocab
