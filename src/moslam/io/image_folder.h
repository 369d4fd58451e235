// A folder of images as a monocular sequence, for videos exported frame by frame and data sets
// without an index file: the images are taken in file-name order at a fixed frame rate.
#pragma once

#include <string>

#include "moslam/io/sequence.h"

namespace moslam::io {

// Whether the file name has an image extension moslam reads: png, jpg, jpeg, pgm, ppm, bmp
// (case-insensitive).
bool HasImageExtension(const std::string& filename);

// The images directly inside `folder` (not its subfolders), sorted by file name (byte-wise, so
// zero-padded numbers sort in order: 000010.png after 000009.png), frame i stamped i / rate_hz
// seconds. Throws InputError for a missing folder, a rate that is not a positive number of Hz,
// or a folder without images.
Sequence ReadImageFolder(const std::string& folder, double rate_hz);

}  // namespace moslam::io
