// TUM RGB-D benchmark sequences (Sturm et al., IROS 2012; https://vision.in.tum.de/data/datasets/
// rgbd-dataset/file_formats): a folder with rgb.txt and depth.txt ("timestamp filename" lines,
// '#' comments), the images they list, and optionally groundtruth.txt.
//
// The RGB and depth streams are not synchronized; frames are formed by the association rule of
// TUM's associate.py, or read from an associations file written by it (the input of ORB-SLAM2's
// rgbd_tum example).
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "moslam/io/sequence.h"

namespace moslam::io {

struct TumRgbdOptions {
  // Seconds: an RGB and a depth stamp are paired only when |t_rgb - (t_depth + offset)| is below
  // this (strictly), as associate.py's --max_difference.
  double max_difference = 0.02;
  // Seconds added to every depth stamp before comparing (associate.py's --offset).
  double offset = 0.0;
  // When non-empty, read frames from this associations file ("t_rgb rgb_path t_depth depth_path"
  // lines, paths relative to the sequence folder) instead of associating rgb.txt and depth.txt.
  std::string associations_path;

  // Throws InputError unless max_difference > 0 and offset are finite.
  void Check() const;
};

// One line of rgb.txt / depth.txt.
struct StampedFile {
  int line = 0;            // line number in the list file
  double timestamp = 0.0;  // seconds
  std::string path;        // resolved against the list file's folder
};

// Reads an rgb.txt / depth.txt list: exactly two fields a line, finite and strictly increasing
// stamps, every listed file present. Errors name the file and line.
std::vector<StampedFile> ReadTumFileList(const std::string& path);

// associate.py's rule: every pair (i, j) with |first[i] - (second[j] + offset)| < max_difference
// is a candidate; candidates are taken in increasing difference (ties by first stamp, then second)
// and accepted when neither stamp is used yet. Returns the accepted (i, j) sorted by first[i].
// Stamps and offset must be finite and max_difference > 0 (CHECK).
std::vector<std::pair<size_t, size_t>> AssociateTimestamps(const std::vector<double>& first,
                                                           const std::vector<double>& second,
                                                           double offset, double max_difference);

// An RGB-D sequence from a TUM folder. Throws InputError for a missing folder or list file, a
// malformed line, a listed image that does not exist, or when no RGB-depth pair is found.
Sequence ReadTumRgbd(const std::string& folder, const TumRgbdOptions& options = {});

}  // namespace moslam::io
