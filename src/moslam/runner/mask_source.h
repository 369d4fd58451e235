// Where the per-frame movable-object mask of `moslam run` comes from (CV_8UC1 of the image's
// size, non-zero = movable; it reaches the ORB extractor through slam::FrameInput::mask):
//
//   none      no mask.
//   files     a folder of mask PNGs named like the frames' images: frame image .../rgb/<stem>.png
//             (or any extension) takes DIR/<stem>.png. A missing file is an InputError naming
//             it, unless `missing_empty` (then the frame has no mask).
//   synth-gt  the synthetic generator's ground truth: per frame <dir>/class/<stem>.png (uint8
//             class ids), where the frame's image is <dir>/rgb/<stem>.png, and
//             classes.txt (in the sequence's root, else in <dir>) with lines `<id> <name> <movable
//             0|1>`. The mask is the pixels whose class is movable: the classes named in `movable`,
//             or, when that is empty, those marked 1 in classes.txt.
//
// Masks are read in the image-loading thread; MaskFor is const and safe to call from any thread.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "moslam/io/sequence.h"

namespace moslam::runner {

enum class MaskSourceKind { kNone, kFiles, kSynthGt };

const char* ToString(MaskSourceKind kind);  // "none", "files", "synth-gt"
std::optional<MaskSourceKind> ParseMaskSourceKind(const std::string& name);

struct MaskOptions {
  MaskSourceKind kind = MaskSourceKind::kNone;
  std::string folder;          // files: the folder of mask PNGs (required there)
  bool missing_empty = false;  // files: a missing mask file means "no mask" instead of an error
  // synth-gt: class names that are movable; empty = the ones classes.txt marks movable.
  std::vector<std::string> movable;
  int dilate_px = 0;  // grow every mask by this many pixels (elliptic element), >= 0
  // InputError naming the command-line option of the first bad value.
  void Check() const;
};

// One line of a synthetic sequence's classes.txt.
struct ClassInfo {
  int id = 0;  // 0..255, the pixel value in class/<stem>.png
  std::string name;
  bool movable = false;
};
// Reads classes.txt; InputError naming file and line for a malformed line, an id outside 0..255,
// or a repeated id or name.
std::vector<ClassInfo> ReadClasses(const std::string& path);

struct FrameMask {
  cv::Mat mask;           // CV_8UC1, 0 / 255; empty: no mask for this frame
  double fraction = 0.0;  // share of movable pixels after dilation, 0..1
  std::string path;       // the file it came from; empty when none
};

class MaskSource {
 public:
  virtual ~MaskSource() = default;
  // The mask of `frame`, whose left image has `image_size`. InputError naming the file when it
  // is missing (unless allowed), unreadable, not 8-bit single-channel, or of another size.
  virtual FrameMask MaskFor(const io::FrameEntry& frame, const cv::Size& image_size) const = 0;
  // For logs and summary.json, e.g. "synth-gt (movable: person, car)".
  virtual std::string Describe() const = 0;
};

// Checks `options` and, for synth-gt, reads classes.txt (InputError when absent,
// or when a name in `movable` is not one of its classes).
std::unique_ptr<MaskSource> MakeMaskSource(const MaskOptions& options,
                                           const io::Sequence& sequence);

// The file a frame's mask has in `folder`: folder/<stem of frame.image_left>.png.
std::string MaskPathFor(const std::string& folder, const io::FrameEntry& frame);

}  // namespace moslam::runner
