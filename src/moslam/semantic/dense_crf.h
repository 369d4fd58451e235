// Fully connected CRF with Gaussian pairwise potentials and mean-field inference (P. Krähenbühl,
// V. Koltun, "Efficient inference in fully connected CRFs with Gaussian edge potentials",
// NIPS 2011), with the depth kernel of the movable-object SLAM paper (Sun et al. 2019): a
// bilateral kernel on position and depth instead of position and colour.
//
// Energy: E(x) = sum_i U_i(x_i) + sum_{i,j} mu(x_i, x_j) sum_m w_m k_m(f_i, f_j), with kernels
//   smoothness  k = exp(-|p_i - p_j|^2 / 2 sxy^2)                                 (positions)
//   appearance  k = exp(-|p_i - p_j|^2 / 2 sxy^2 - |I_i - I_j|^2 / 2 srgb^2)       (colour/grey)
//   depth       k = exp(-|p_i - p_j|^2 / 2 sxy^2 - (z_i - z_j)^2 / 2 sd^2)         (metres)
// and mu the Potts model [x_i != x_j] unless a label-compatibility matrix is given. As in
// Krähenbühl's released code (version 2), each kernel matrix K is normalized symmetrically,
// D^-1/2 K D^-1/2 with D = diag(K 1), and includes the j = i term; the mean-field update is
//   Q_i(l) ~ exp(-U_i(l) - sum_l' mu(l, l') sum_m w_m (D^-1/2 K_m D^-1/2 Q)_i(l')).
// Kernels are filtered with the permutohedral lattice (permutohedral_lattice.h), built once per
// image and per kernel, or, for the smoothness kernel with few labels, with an exact separable
// Gaussian blur (crf_kernels.h). All labels travel through a filter together, and only L - 1 of
// them: the last label's message follows from linearity, since the Q(l) sum to 1. Results are
// bit-identical for any number of threads (see crf_simd.h for the instruction sets).
//
// Pixels whose depth is invalid (0, negative or not finite) take no part in the depth kernel:
// they neither pull their neighbours nor are pulled through it; the other kernels still apply.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace moslam {
class YamlFile;
}

namespace moslam::semantic {

class ThreadPool;

struct DenseCrfOptions {
  // Mean-field iterations (Krähenbühl and Koltun use 5; so did the paper's authors' setup).
  int iterations = 5;

  // Smoothness kernel (position only): removes small isolated regions.
  bool smoothness = true;
  float smoothness_sxy = 3.0f;  // pixels
  float smoothness_weight = 3.0f;
  // How the smoothness kernel is filtered: "lattice" (like the other kernels), "separable" (an
  // exact Gaussian blur truncated at 3 sxy, cheaper with few labels) or "auto": separable when
  // sxy <= 10 and there are at most 5 labels.
  std::string smoothness_filter = "auto";

  // Appearance kernel (position + colour, or + intensity for grey images): nearby pixels of
  // similar colour take the same label. The paper's configuration "c".
  bool appearance = true;
  float appearance_sxy = 80.0f;   // pixels
  float appearance_srgb = 13.0f;  // 8-bit intensity levels, per channel
  float appearance_weight = 10.0f;

  // Depth kernel (position + metric depth): nearby pixels at similar depth take the same label.
  // The paper's configuration "d" (with smoothness, without appearance) or "c,d" (all three).
  // sd is in metres; 0.1 m separates objects standing apart while tolerating the depth change
  // along a surface within sxy at the distances of indoor RGB-D scenes.
  bool depth = false;
  float depth_sxy = 10.0f;  // pixels
  float depth_sd_m = 0.1f;  // metres
  float depth_weight = 15.0f;

  // Probabilities are clamped to [min_probability, 1] before -log, so that a zero probability
  // gives a large but finite energy (-log 1e-5 = 11.5).
  float min_probability = 1e-5f;

  // Label compatibility mu(l, l') as L x L numbers, row-major; empty means Potts (1 - identity).
  // Must match the number of labels of the unaries when given.
  std::vector<double> compatibility;

  // Threads used by one inference, the caller's included. The result does not depend on it.
  int num_threads = 2;

  // Throws InputError naming the option when a value is out of range.
  void Check() const;
};

// Reads the options under `prefix` (e.g. "crf." for crf.iterations, crf.appearance_sxy, ...;
// the keys are the field names above) from `file`, keeping defaults for absent keys, then Check()s.
void ReadDenseCrfOptions(YamlFile& file, const std::string& prefix, DenseCrfOptions* options);
// Loads a file holding only the options under "crf."; an unknown key is an InputError.
DenseCrfOptions LoadDenseCrfOptions(const std::string& path);

// Per-pixel unary input for L labels (2 to 32), CV_32F, in either layout:
//   planar       3-D cv::Mat of sizes {L, H, W} (what cv::dnn produces, without the batch);
//   interleaved  2-D H x W cv::Mat with L channels (CV_32FC(L)), e.g. from an H x W x L array.
struct Unaries {
  enum class Kind { kProbabilities, kEnergies };
  Kind kind = Kind::kProbabilities;
  cv::Mat values;

  // Probabilities p (need not be normalized); the CRF uses -log(max(p, min_probability)).
  static Unaries FromProbabilities(cv::Mat probabilities);
  // Energies U (lower is more likely), used as they are.
  static Unaries FromEnergies(cv::Mat energies);

  int num_labels() const;
  cv::Size size() const;
};

struct CrfResult {
  cv::Mat marginals;  // 3-D CV_32F {L, H, W}: Q_i(l), summing to 1 over l.
  cv::Mat labels;     // H x W CV_8U: argmax_l Q_i(l) (the lowest label on ties).
};

// Plane l of a planar {L, H, W} CV_32F matrix, as an H x W header sharing its data.
cv::Mat LabelPlane(const cv::Mat& planar, int label);

// Reusable inference: keeps its threads and buffers between images of a sequence.
class DenseCrf {
 public:
  // Throws InputError when the options are invalid.
  explicit DenseCrf(const DenseCrfOptions& options);
  ~DenseCrf();
  DenseCrf(const DenseCrf&) = delete;
  DenseCrf& operator=(const DenseCrf&) = delete;

  const DenseCrfOptions& options() const { return options_; }

  // image: 8UC3 (any channel order: only colour differences matter) or 8UC1 (grey), H x W >= 1.
  // depth_m: CV_32F H x W in metres, required when the depth kernel is enabled, else ignored.
  // Throws InputError when sizes or types disagree.
  CrfResult Infer(const cv::Mat& image, const cv::Mat& depth_m, const Unaries& unaries);
  // The same, reusing the result's buffers when their sizes fit (a video stream).
  void Infer(const cv::Mat& image, const cv::Mat& depth_m, const Unaries& unaries,
             CrfResult* result);

 private:
  struct Workspace;
  // The enabled kernels for this image; `channels` is the number of filtered channels.
  void PrepareKernels(const cv::Mat& image, const cv::Mat& depth_m, int channels);
  DenseCrfOptions options_;
  std::unique_ptr<ThreadPool> pool_;
  std::unique_ptr<Workspace> workspace_;
};

// One-shot convenience: DenseCrf(options).Infer(image, depth_m, unaries).
CrfResult InferDenseCrf(const cv::Mat& image, const cv::Mat& depth_m, const Unaries& unaries,
                        const DenseCrfOptions& options);

}  // namespace moslam::semantic
