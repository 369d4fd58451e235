// Synthetic binary descriptors for the vocab tests and benchmark, so that they run without images:
// random 256-bit descriptors, noisy copies (bit flips), and clustered sets with a known
// hierarchy (prototypes, sub-prototypes, samples).
#pragma once

#include <cstdint>
#include <cstring>
#include <vector>

#include <opencv2/core.hpp>

namespace moslam::vocab::test {

// n x 32 uniformly random descriptors.
inline cv::Mat RandomDescriptors(int n, cv::RNG& rng) {
  cv::Mat d(n, 32, CV_8UC1);
  rng.fill(d, cv::RNG::UNIFORM, 0, 256);
  return d;
}

// Flips `bits` distinct random bits of a 32-byte descriptor.
inline void FlipBits(uint8_t* d, int bits, cv::RNG& rng) {
  bool flipped[256] = {};
  for (int done = 0; done < bits;) {
    const int b = rng.uniform(0, 256);
    if (flipped[b]) continue;
    flipped[b] = true;
    d[b / 8] ^= static_cast<uint8_t>(1u << (b % 8));
    ++done;
  }
}

// A copy of `image` whose rows have `bits` flipped bits each, and whose first `outliers` rows
// are replaced by random descriptors (what a second view of a place looks like to BoW).
inline cv::Mat NoisyCopy(const cv::Mat& image, int bits, int outliers, cv::RNG& rng) {
  cv::Mat copy = image.clone();
  for (int r = 0; r < copy.rows; ++r) FlipBits(copy.ptr<uint8_t>(r), bits, rng);
  if (outliers > 0) RandomDescriptors(outliers, rng).copyTo(copy.rowRange(0, outliers));
  return copy;
}

// `groups` random prototypes; each has `subgroups` sub-prototypes `sub_bits` flips away; each of
// those has `samples` descriptors `sample_bits` flips away. Rows are grouped by sub-prototype.
inline cv::Mat ClusteredDescriptors(int groups, int subgroups, int samples, int sub_bits,
                                    int sample_bits, cv::RNG& rng) {
  cv::Mat prototypes = RandomDescriptors(groups, rng);
  cv::Mat out(groups * subgroups * samples, 32, CV_8UC1);
  int row = 0;
  for (int g = 0; g < groups; ++g) {
    for (int s = 0; s < subgroups; ++s) {
      uint8_t sub[32];
      std::memcpy(sub, prototypes.ptr<uint8_t>(g), 32);
      FlipBits(sub, sub_bits, rng);
      for (int i = 0; i < samples; ++i, ++row) {
        std::memcpy(out.ptr<uint8_t>(row), sub, 32);
        FlipBits(out.ptr<uint8_t>(row), sample_bits, rng);
      }
    }
  }
  return out;
}

// Splits the rows of `all` into `images` matrices of consecutive rows (the last one takes the
// remainder) — training "images" for a vocabulary.
inline std::vector<cv::Mat> SplitRows(const cv::Mat& all, int images) {
  std::vector<cv::Mat> out;
  const int per = all.rows / images;
  for (int i = 0; i < images; ++i) {
    const int end = i + 1 == images ? all.rows : (i + 1) * per;
    out.push_back(all.rowRange(i * per, end).clone());
  }
  return out;
}

}  // namespace moslam::vocab::test
