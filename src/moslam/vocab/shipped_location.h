// Where the vocabulary shipped with the repository (data/vocab/moslam_orb.mvoc,
// docs/VOCABULARY.md) is, for a program started from any folder. Looking only in the working
// folder made `moslam run` started elsewhere run without relocalization and loop closing behind
// one warning line, and a lost RGB-D tracker then resumed from its reference keyframe alone at a
// pose 1.4 m off (w_xyz seed 28; docs/RUNNING.md "Deterministic runs and the mapping thread").
#pragma once

#include <filesystem>
#include <vector>

namespace moslam::vocab {

inline constexpr char kShippedVocabulary[] = "data/vocab/moslam_orb.mvoc";

// The places looked in, in order: `cwd`/kShippedVocabulary, then the same path under the folder
// of the executable `exe` and each of the 4 folders above it (a build tree inside the repository:
// build/apps/moslam/moslam is three below its root). An empty `exe` adds nothing.
std::vector<std::filesystem::path> ShippedVocabularyCandidates(const std::filesystem::path& cwd,
                                                               const std::filesystem::path& exe);

// The first candidate that is a regular file; empty when there is none.
std::filesystem::path FindShippedVocabulary(const std::filesystem::path& cwd,
                                            const std::filesystem::path& exe);

// This process's executable (Linux: /proc/self/exe); empty where it cannot be read.
std::filesystem::path CurrentExecutable();

}  // namespace moslam::vocab
