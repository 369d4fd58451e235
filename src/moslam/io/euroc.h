// EuRoC MAV sequences (Burri et al., IJRR 2016), ASL folder format: <folder>/mav0/cam0/data.csv
// and mav0/cam1/data.csv ("#timestamp [ns],filename" header, then "stamp_ns,filename" lines),
// images under mav0/camX/data/, ground truth in mav0/state_groundtruth_estimate0/data.csv.
#pragma once

#include <string>

#include "moslam/io/sequence.h"

namespace moslam::io {

struct EurocOptions {
  // Use only cam0 even when cam1 is present. Without mav0/cam1/ the sequence is monocular anyway.
  bool monocular = false;
};

// `folder` is the sequence folder holding mav0/ (or mav0/ itself). Stereo frames pair cam0 and
// cam1 entries with equal nanosecond stamps; a cam0 entry without a cam1 partner is dropped with a
// warning. Stamps are nanoseconds in the files and seconds in the frames. Throws InputError for a
// missing folder or data.csv, a malformed line (field count, non-integer or negative stamp),
// non-increasing stamps, a listed image that does not exist, or no stereo pair at all.
Sequence ReadEuroc(const std::string& folder, const EurocOptions& options = {});

}  // namespace moslam::io
