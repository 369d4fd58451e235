// Where the per-frame movable-object mask of `moslam run` comes from (CV_8UC1 of the image's
// size, non-zero = movable; it reaches the ORB extractor through slam::FrameInput::mask):
//
//   none      no mask.
//   onnx      an ONNX semantic-segmentation network, described by a model card
//   detector  an object detector's boxes (Darknet or ONNX), described by a model card
//   model     a segmentation network of the weakly supervised pipeline run by libtorch, described
//             by a model card of type torch (net/torch_mask_provider.h); the card defaults to
//             kDefaultTorchCard when that file exists
//             (all three: semantic/mask_provider.h, refined per RefineOptions, --crf none|c|d|cd)
//   files     a folder of mask PNGs named like the frames' images: frame image .../rgb/<stem>.png
//             (or any extension) takes DIR/<stem>.png. A missing file is an InputError naming
//             it, unless `missing_empty` (then the frame has no mask).
//   synth-gt  the synthetic generator's ground truth: per frame <dir>/class/<stem>.png (uint8
//             class ids), where the frame's image is <dir>/rgb/<stem>.png, and
//             classes.txt (in the sequence's root, else in <dir>) with lines `<id> <name> <movable
//             0|1>`. The mask is the pixels whose class is movable: the classes named in `movable`,
//             or, when that is empty, those marked 1 in classes.txt.
//
// Masks are computed in the segmentation stage's threads (segmentation_stage.h), one frame at a
// time, through Predict() and Refine(). The file-based sources' MaskFor is const and safe from any
// thread.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "moslam/io/sequence.h"
#include "moslam/semantic/mask_refine.h"

namespace moslam::semantic {
struct Prediction;  // semantic/mask_provider.h
}  // namespace moslam::semantic

namespace moslam::runner {

enum class MaskSourceKind { kNone, kFiles, kSynthGt, kOnnx, kDetector, kModel };

// "none", "files", "synth-gt", "onnx", "detector", "model"
const char* ToString(MaskSourceKind kind);
std::optional<MaskSourceKind> ParseMaskSourceKind(const std::string& name);
// onnx, detector and model: the sources that run a network described by a model card.
bool IsModelSource(MaskSourceKind kind);

// The card `--mask-source model` uses without --model-card (relative to the working directory).
inline constexpr const char* kDefaultTorchCard = "configs/models/weak_camvid.yaml";

struct MaskOptions {
  MaskSourceKind kind = MaskSourceKind::kNone;
  std::string folder;          // files: the folder of mask PNGs (required there)
  bool missing_empty = false;  // files: a missing mask file means "no mask" instead of an error
  // synth-gt, onnx, detector, model: class names that are movable; empty = the ones classes.txt
  // (or the model card) marks movable.
  std::vector<std::string> movable;
  // onnx, detector, model: the card's path (required for onnx and detector; model defaults to
  // kDefaultTorchCard).
  std::string model_card;
  // onnx, detector, model: CRF kernels; nullopt = the card's refine settings (no CRF unless set
  // there).
  std::optional<semantic::CrfMode> crf;
  int dilate_px = 0;  // grow every mask by this many pixels (elliptic), 0..semantic::kMaxDilatePx
  // model: libtorch's intra-op threads in place of the card's `threads`; 0: the card's. `moslam
  // run --deterministic` sets 1: libtorch's results depend on its thread count (the shipped
  // person network's mask differs in a pixel or so between 1 and 2 threads on an AMD EPYC with
  // AVX2, 2026-12-07), and a deterministic run must not.
  int network_threads = 0;
  // InputError naming the command-line option of the first bad value.
  void Check() const;
};

struct FrameMask {
  cv::Mat mask;             // CV_8UC1, 0 / 255; empty: no mask for this frame
  double fraction = 0.0;    // share of movable pixels after dilation, 0..1
  std::string path;         // the file it came from; empty when none
  double network_ms = 0.0;  // model sources: pre-processing and inference
  double crf_ms = 0.0;      // model sources: the CRF
  int frame_index = 0;      // set by sources that need it between Predict() and Refine()
  // Pipelined model sources: the network's output between Predict() and Refine() (mask empty).
  std::shared_ptr<semantic::Prediction> pending;
};

class MaskSource {
 public:
  virtual ~MaskSource() = default;
  // The mask of `frame`, whose left image has `image_size`. InputError naming the file when it
  // is missing (unless allowed), unreadable, not 8-bit single-channel, or of another size.
  virtual FrameMask MaskFor(const io::FrameEntry& frame, const cv::Size& image_size) const = 0;
  // The mask of a loaded frame (image: its left image as tracking gets it; depth: CV_32F metres
  // or empty) in two steps, so that a network's next frame runs while the CRF refines this one:
  // Predict() (the network) then Refine() (the CRF and the rest). Sources that say Pipelined()
  // (networks) leave FrameMask::pending to Refine(); the file-based ones read MaskFor(frame,
  // image.size()) in Predict() and have nothing to refine. Each step is called by one thread at a
  // time.
  virtual bool Pipelined() const { return false; }
  virtual FrameMask Predict(const io::FrameEntry& frame, const cv::Mat& image,
                            const cv::Mat& depth) {
    (void)depth;
    return MaskFor(frame, image.size());
  }
  virtual void Refine(FrameMask* mask, const cv::Mat& image, const cv::Mat& depth) {
    (void)mask;
    (void)image;
    (void)depth;
  }
  // For logs and summary.json, e.g. "synth-gt (movable: person, car)".
  virtual std::string Describe() const = 0;
};

// Checks `options` and, for synth-gt, reads classes.txt (InputError when absent, or when a name
// in `movable` is not one of its classes); for onnx, detector and model, loads the card and the
// network (InputError naming the card or the model file).
std::unique_ptr<MaskSource> MakeMaskSource(const MaskOptions& options,
                                           const io::Sequence& sequence);

// The file a frame's mask has in `folder`: folder/<stem of frame.image_left>.png.
std::string MaskPathFor(const std::string& folder, const io::FrameEntry& frame);

}  // namespace moslam::runner
