// ORB descriptors of image files, for training and evaluating vocabularies (`moslam vocab train`,
// tools/vocab_eval): the project's extractor (feature::OrbExtractor, ORB-SLAM2 defaults), one
// extractor per thread, with progress lines.
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "moslam/feature/orb_options.h"

namespace moslam::vocab {

// Image files (.png, .jpg, .jpeg, .pgm, .ppm, .bmp) directly in `dir`, sorted by name.
// Throws InputError naming `dir` when it is not a directory or holds no image.
std::vector<std::string> ListImages(const std::string& dir);

// Descriptors (N x 32, CV_8UC1) of each image, read as grey; result[i] belongs to paths[i] and
// does not depend on `threads`. Throws InputError naming an unreadable image.
std::vector<cv::Mat> ExtractDescriptors(const std::vector<std::string>& paths,
                                        const feature::OrbExtractorOptions& options, int threads,
                                        const std::string& progress_label = "ORB extraction");

}  // namespace moslam::vocab
