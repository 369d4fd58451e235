// Fuzz harnesses of moslam's parsers (issue 31, docs/ROBUSTNESS.md "Fuzzing the parsers").
//
// One harness per parser. Each takes arbitrary bytes as the content of the file the parser reads
// and calls it; malformed input must end in moslam::InputError, which the harness swallows.
// Anything else escapes on purpose: another exception type terminates the process, a
// MOSLAM_CHECK aborts, and in the fuzz build AddressSanitizer / UBSan report memory errors and
// undefined behaviour. The same harnesses run three ways:
//   - libFuzzer binaries `fuzz_<name>` (clang, MOSLAM_BUILD_FUZZERS, scripts/fuzz.sh);
//   - the `fuzz/corpus` test in every build, which replays the generated seeds and every
//     committed finding (fuzz/regressions/<name>/), so a fixed finding stays fixed;
//   - `moslam_fuzz_seeds`, which writes the seed corpus the fuzzers start from.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "moslam/mapio/map_file.h"

namespace moslam::fuzz {

struct FuzzTarget {
  const char* name;       // fuzz_<name>, fuzz/regressions/<name>/
  const char* file_name;  // the scratch file the bytes are written to (parsers look at names)
  const char* what;       // the parser, for messages and docs
  // Parses the file at `path` (the input's bytes); `folder` holds it and the files a list may
  // name (scratch folder of this process). Throws what the parser throws.
  void (*parse)(const std::string& path, const std::string& folder);
};

// Every harness, in a fixed order.
const std::vector<FuzzTarget>& Targets();
// The harness called `name`; CHECK-fails for an unknown name (a build error of the fuzzers).
const FuzzTarget& FindTarget(std::string_view name);

// Runs `target` on `data`: true when the parser accepted it, false when it threw InputError.
// The scratch folder is made once per process (under TMPDIR, removed at exit).
bool RunOne(const FuzzTarget& target, const uint8_t* data, size_t size);
// `error` (may be null) receives the InputError's message.
bool RunOne(const FuzzTarget& target, const std::string& bytes, std::string* error = nullptr);

// The identity the map harness expects (an RGB-D camera, no vocabulary); its seeds carry it.
mapio::MapIdentity FuzzMapIdentity();

// Writes the seed corpus of every target into `out_dir`/<name>/ (created): the settings files
// and model cards of `source_dir`/configs, small valid lists, calibrations and trajectories, a
// trained vocabulary in both formats, and a map body. Returns the number of files written.
int WriteSeeds(const std::string& source_dir, const std::string& out_dir);

}  // namespace moslam::fuzz
