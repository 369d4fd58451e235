// TEMPORARY stand-in, replaced by the real plot at merge (see plot.h).
#include "moslam/eval/plot.h"

#include "moslam/util/error.h"

namespace moslam::eval {

void WriteTrajectoryPlot(const TrajectoryPlotData& /*data*/, const std::string& /*path*/) {
  throw InputError("plotting not available yet");
}

}  // namespace moslam::eval
