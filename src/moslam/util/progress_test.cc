#include "moslam/util/progress.h"

#include <memory>
#include <sstream>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>

namespace moslam {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;

TEST(Progress, ShowsCountPercentRateAndEta) {
  const std::string line = FormatProgress("frames", 200, 800, 10.0, false, "frames");
  EXPECT_THAT(line, HasSubstr("200/800"));
  EXPECT_THAT(line, HasSubstr("25%"));
  EXPECT_THAT(line, HasSubstr("20.0 frames/s"));
  EXPECT_THAT(line, HasSubstr("ETA 30 s"));  // 600 left at 20/s
}

TEST(Progress, BarFillsInProportion) {
  const std::string half = FormatProgress("x", 50, 100, 1.0, true);
  EXPECT_THAT(half, HasSubstr("[============>           ]"));
  const std::string full = FormatProgress("x", 100, 100, 4.0, true);
  EXPECT_THAT(full, HasSubstr("[========================]"));
  EXPECT_THAT(full, HasSubstr("in 4 s"));
}

TEST(Progress, UnknownTotalHasRateButNoEta) {
  const std::string line = FormatProgress("x", 30, 0, 3.0, true);
  EXPECT_THAT(line, HasSubstr("10.0 it/s"));
  EXPECT_THAT(line, Not(HasSubstr("ETA")));
  EXPECT_THAT(line, Not(HasSubstr("%")));
}

TEST(Progress, LongEtaIsInMinutesOrHours) {
  EXPECT_THAT(FormatProgress("x", 1, 1000, 1.0, false), HasSubstr("ETA 16:39 min"));
  EXPECT_THAT(FormatProgress("x", 1, 100000, 1.0, false), HasSubstr("ETA 27:46 h"));
}

TEST(Progress, ObjectLogsPeriodicLinesAndOneFinalLine) {
  std::ostringstream captured;
  auto previous = spdlog::default_logger();
  spdlog::set_default_logger(std::make_shared<spdlog::logger>(
      "capture", std::make_shared<spdlog::sinks::ostream_sink_mt>(captured)));
  {
    Progress progress("work", 3, 0.0);  // interval 0: every update prints (stderr is no tty here)
    for (size_t i = 1; i <= 3; ++i) progress.Update(i);
    progress.Finish();
    progress.Finish();  // idempotent: no second final line
  }                     // the destructor must not print again either
  spdlog::set_default_logger(previous);
  const std::string out = captured.str();
  EXPECT_THAT(out, HasSubstr("work  3/3 100%"));
  size_t finals = 0;
  for (size_t pos = out.find("in 0 s"); pos != std::string::npos;
       pos = out.find("in 0 s", pos + 1)) {
    ++finals;
  }
  // One from Update(3) when not on a terminal, one from Finish.
  EXPECT_LE(finals, 2u);
  EXPECT_GE(finals, 1u);
}

}  // namespace
}  // namespace moslam
