#include "moslam/synth/texture.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "moslam/synth/rng.h"
#include "moslam/util/check.h"
#include "moslam/util/error.h"

namespace moslam::synth {
namespace {

using Colour = std::array<float, 3>;

// Tileable value noise: a random lattice of `cells` x `cells` values, smoothly interpolated and
// wrapped at the borders so the texture repeats without seams.
class Lattice {
 public:
  Lattice(Rng& rng, int cells) : cells_(cells), v_(static_cast<size_t>(cells * cells)) {
    for (float& x : v_) x = static_cast<float>(rng.Uniform());
  }
  // u, v in texture units [0, 1).
  float At(float u, float v) const {
    const float x = u * cells_, y = v * cells_;
    const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
    float fx = x - x0, fy = y - y0;
    fx = fx * fx * (3 - 2 * fx);
    fy = fy * fy * (3 - 2 * fy);
    const float a = Get(x0, y0), b = Get(x0 + 1, y0), c = Get(x0, y0 + 1), d = Get(x0 + 1, y0 + 1);
    return (a * (1 - fx) + b * fx) * (1 - fy) + (c * (1 - fx) + d * fx) * fy;
  }

 private:
  float Get(int x, int y) const {
    x = ((x % cells_) + cells_) % cells_;
    y = ((y % cells_) + cells_) % cells_;
    return v_[static_cast<size_t>(y * cells_ + x)];
  }
  int cells_;
  std::vector<float> v_;
};

// Fractal noise: octaves of doubling frequency and `gain` amplitude, as a float image in [0, 1].
cv::Mat Fractal(Rng& rng, int size, int base_cells, int octaves, float gain) {
  cv::Mat out(size, size, CV_32F, cv::Scalar(0));
  float amplitude = 1.0f, total = 0.0f;
  // At least one octave: a lattice finer than the image (small test textures) would leave no
  // octave at all and a 0/0 texture, which rendered black.
  int cells = std::min(base_cells, size);
  for (int o = 0; o < octaves && cells <= size; ++o, cells *= 2, amplitude *= gain) {
    const Lattice lattice(rng, cells);
    for (int y = 0; y < size; ++y) {
      float* row = out.ptr<float>(y);
      for (int x = 0; x < size; ++x) {
        row[x] += amplitude * lattice.At((x + 0.5f) / size, (y + 0.5f) / size);
      }
    }
    total += amplitude;
  }
  out /= total;
  return out;
}

Colour RandomColour(Rng& rng, float lo, float hi) {
  return {static_cast<float>(rng.Uniform(lo, hi)), static_cast<float>(rng.Uniform(lo, hi)),
          static_cast<float>(rng.Uniform(lo, hi))};
}

Colour Mix(const Colour& a, const Colour& b, float s) {
  return {a[0] + (b[0] - a[0]) * s, a[1] + (b[1] - a[1]) * s, a[2] + (b[2] - a[2]) * s};
}

void Put(cv::Mat& img, int x, int y, const Colour& c, float shade) {
  auto& px = img.at<cv::Vec3b>(y, x);
  for (int k = 0; k < 3; ++k) px[k] = cv::saturate_cast<uchar>(255.0f * c[k] * shade);
}

// Colour field: two colours mixed by fractal noise, shaded by a finer noise.
cv::Mat Mottled(Rng& rng, int size, const Colour& a, const Colour& b, int cells, float contrast) {
  const cv::Mat mix = Fractal(rng, size, cells, 6, 0.6f);
  const cv::Mat fine = Fractal(rng, size, cells * 8, 3, 0.5f);
  cv::Mat img(size, size, CV_8UC3);
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) {
      const float m = std::clamp((mix.at<float>(y, x) - 0.5f) * contrast + 0.5f, 0.0f, 1.0f);
      Put(img, x, y, Mix(a, b, m), 0.8f + 0.4f * fine.at<float>(y, x));
    }
  }
  return img;
}

cv::Mat Bricks(Rng& rng, int size) {
  const Colour brick = RandomColour(rng, 0.35f, 0.75f), mortar = RandomColour(rng, 0.6f, 0.85f);
  const int rows = 8 << rng.Index(2), cols = rows / 2;
  const cv::Mat noise = Fractal(rng, size, 8, 6, 0.6f);
  cv::Mat img(size, size, CV_8UC3);
  std::vector<float> tint(static_cast<size_t>(rows * cols * 2));
  for (float& t : tint) t = static_cast<float>(rng.Uniform(0.75, 1.2));
  const float bh = static_cast<float>(size) / rows, bw = static_cast<float>(size) / cols;
  for (int y = 0; y < size; ++y) {
    const int r = static_cast<int>(y / bh);
    for (int x = 0; x < size; ++x) {
      const float shift = (r % 2) * bw / 2;
      const float xs = std::fmod(x + shift, static_cast<float>(size));
      const int c = static_cast<int>(xs / bw);
      const float fy = y - r * bh, fx = xs - c * bw;
      const bool joint = fy < 0.1f * bh || fx < 0.06f * bw;
      const float n = noise.at<float>(y, x);
      if (joint) {
        Put(img, x, y, mortar, 0.8f + 0.3f * n);
      } else {
        Put(img, x, y, brick, tint[static_cast<size_t>(r * cols + c)] * (0.7f + 0.5f * n));
      }
    }
  }
  return img;
}

cv::Mat Wood(Rng& rng, int size) {
  const Colour light = RandomColour(rng, 0.55f, 0.8f);
  const Colour dark = {light[0] * 0.55f, light[1] * 0.45f, light[2] * 0.35f};
  const cv::Mat warp = Fractal(rng, size, 4, 5, 0.55f);
  const cv::Mat fine = Fractal(rng, size, 64, 3, 0.5f);
  const int planks = 4 << rng.Index(2);
  const float rings = static_cast<float>(rng.Uniform(20, 40));
  cv::Mat img(size, size, CV_8UC3);
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) {
      const int plank = x * planks / size;
      const float u = static_cast<float>(y) / size + 0.37f * plank;
      const float g = 0.5f + 0.5f * std::sin(2 * static_cast<float>(M_PI) *
                                             (u * rings + 3.0f * warp.at<float>(y, x)));
      const bool seam = (x * planks) % size < planks * 2;
      Put(img, x, y, Mix(light, dark, g * g),
          (seam ? 0.5f : 1.0f) * (0.85f + 0.3f * fine.at<float>(y, x)));
    }
  }
  return img;
}

// Clothing: plaid, stripes or a scatter of printed motifs, over a woven micro-texture.
cv::Mat Clothing(Rng& rng, int size) {
  const Colour a = RandomColour(rng, 0.1f, 0.9f), b = RandomColour(rng, 0.1f, 0.9f);
  const Colour c = RandomColour(rng, 0.0f, 1.0f);
  const int style = rng.Index(3);
  const int period = size / (4 << rng.Index(3));
  const cv::Mat noise = Fractal(rng, size, 8, 6, 0.6f);
  cv::Mat img(size, size, CV_8UC3);
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) {
      const bool sx = (x % period) < period / 3, sy = (y % period) < period / 4;
      Colour col = a;
      if (style == 0) col = sx && sy ? c : (sx || sy ? b : a);                      // plaid
      if (style == 1) col = sy ? b : ((y % period) > period * 3 / 4 ? c : a);       // stripes
      if (style == 2) col = Mix(a, b, noise.at<float>(y, x) > 0.5f ? 1.0f : 0.0f);  // camouflage
      const float weave = ((x + y) % 4 < 2) ? 0.92f : 1.05f;
      Put(img, x, y, col, weave * (0.75f + 0.5f * noise.at<float>(y, x)));
    }
  }
  if (style == 2 || rng.Uniform() < 0.5) {  // printed motifs: circles and bars of many sizes
    const int motifs = 20 + rng.Index(40);
    for (int i = 0; i < motifs; ++i) {
      const Colour m = RandomColour(rng, 0.0f, 1.0f);
      const cv::Scalar s(255 * m[0], 255 * m[1], 255 * m[2]);
      const cv::Point p(rng.Index(size), rng.Index(size));
      const int r = 2 + rng.Index(size / 12);
      if (rng.Uniform() < 0.5) {
        cv::circle(img, p, r, s, rng.Uniform() < 0.5 ? -1 : 2, cv::LINE_8);
      } else {
        cv::rectangle(img, p, p + cv::Point(r * 2, r), s, -1, cv::LINE_8);
      }
    }
  }
  return img;
}

// Posters and screens: a mottled backdrop with blocks, discs and "text" lines at several scales.
cv::Mat Poster(Rng& rng, int size) {
  cv::Mat img =
      Mottled(rng, size, RandomColour(rng, 0.2f, 1.0f), RandomColour(rng, 0.0f, 0.8f), 2, 2.0f);
  for (int i = 0; i < 25; ++i) {
    const Colour m = RandomColour(rng, 0.0f, 1.0f);
    const cv::Scalar s(255 * m[0], 255 * m[1], 255 * m[2]);
    const cv::Point p(rng.Index(size), rng.Index(size));
    const int r = 3 + rng.Index(size / 6);
    switch (rng.Index(3)) {
      case 0:
        cv::circle(img, p, r, s, -1, cv::LINE_8);
        break;
      case 1:
        cv::rectangle(img, p, p + cv::Point(r, r * 2 / 3), s, -1, cv::LINE_8);
        break;
      default:
        for (int l = 0; l < 6; ++l) {
          const cv::Point q = p + cv::Point(0, l * 6);
          cv::line(img, q, q + cv::Point(r, 0), s, 2, cv::LINE_8);
        }
    }
  }
  return img;
}

// Facades: a wall colour with a grid of dark windows and frames.
cv::Mat Facade(Rng& rng, int size) {
  cv::Mat img =
      Mottled(rng, size, RandomColour(rng, 0.4f, 0.9f), RandomColour(rng, 0.3f, 0.7f), 4, 1.5f);
  const int n = 4 << rng.Index(2), cell = size / n;
  const Colour glass = RandomColour(rng, 0.05f, 0.35f);
  for (int r = 0; r < n; ++r) {
    for (int c = 0; c < n; ++c) {
      const cv::Point p(c * cell + cell / 4, r * cell + cell / 5);
      const cv::Point q = p + cv::Point(cell / 2, cell * 3 / 5);
      const float t = static_cast<float>(rng.Uniform(0.6, 1.4));
      cv::rectangle(img, p, q,
                    cv::Scalar(255 * glass[0] * t, 255 * glass[1] * t, 255 * glass[2] * t), -1,
                    cv::LINE_8);
      cv::rectangle(img, p, q, cv::Scalar(230, 230, 225), 2, cv::LINE_8);
    }
  }
  return img;
}

Colour SkinTone(Rng& rng) {
  const float t = static_cast<float>(rng.Uniform(0.35, 0.95));
  return {t, t * 0.78f, t * 0.62f};
}

}  // namespace

cv::Mat MakeProceduralTexture(TextureKind kind, uint64_t seed, int size) {
  MOSLAM_CHECK(size >= 64 && (size & (size - 1)) == 0) << "texture size " << size;
  Rng rng(seed, static_cast<uint64_t>(kind) + 1);
  switch (kind) {
    case TextureKind::kWall:
      // Painted office walls: faint plaster mottle, rarely brick. A feature-rich wall everywhere
      // would give an unmasked tracker so many static points that people never dominate the
      // view, unlike TUM's fr3 office, where the people carry much of the texture.
      return rng.Uniform() < 0.15 ? Bricks(rng, size)
                                  : Mottled(rng, size, RandomColour(rng, 0.6f, 0.95f),
                                            RandomColour(rng, 0.5f, 0.85f), 4, 1.2f);
    case TextureKind::kFloor:
      return rng.Uniform() < 0.5 ? Wood(rng, size)
                                 : Mottled(rng, size, RandomColour(rng, 0.2f, 0.6f),
                                           RandomColour(rng, 0.1f, 0.5f), 16, 3.0f);
    case TextureKind::kCeiling:
      return Bricks(rng, size);
    case TextureKind::kWood:
      return Wood(rng, size);
    case TextureKind::kPoster:
      return Poster(rng, size);
    case TextureKind::kClothing:
      return Clothing(rng, size);
    case TextureKind::kTrousers:
      return Mottled(rng, size, RandomColour(rng, 0.05f, 0.4f), RandomColour(rng, 0.2f, 0.7f), 32,
                     3.0f);
    case TextureKind::kSkin: {
      const Colour s = SkinTone(rng);
      return Mottled(rng, size, s, {s[0] * 0.8f, s[1] * 0.7f, s[2] * 0.7f}, 8, 2.0f);
    }
    case TextureKind::kHair: {
      const Colour h = RandomColour(rng, 0.05f, 0.45f);
      return Mottled(rng, size, h, {h[0] * 0.5f, h[1] * 0.5f, h[2] * 0.5f}, 32, 3.0f);
    }
    case TextureKind::kCarPaint:
      return Mottled(rng, size, RandomColour(rng, 0.1f, 0.95f), RandomColour(rng, 0.1f, 0.95f), 4,
                     1.0f);
    case TextureKind::kRoad:
      return Mottled(rng, size, {0.35f, 0.35f, 0.37f}, {0.2f, 0.2f, 0.22f}, 32, 3.0f);
    case TextureKind::kFacade:
      return Facade(rng, size);
    case TextureKind::kCount:
      break;
  }
  MOSLAM_CHECK(false) << "bad texture kind";
  return {};
}

TextureSet TextureSet::Procedural(uint64_t seed, int per_kind, int size) {
  MOSLAM_CHECK_GT(per_kind, 0);
  TextureSet set;
  for (int k = 0; k < static_cast<int>(TextureKind::kCount); ++k) {
    for (int i = 0; i < per_kind; ++i) {
      const auto kind = static_cast<TextureKind>(k);
      const uint64_t s = Rng::Mix(seed * 1000003ULL + static_cast<uint64_t>(k * 131 + i));
      set.Add({kind, "procedural:" + std::to_string(k) + ":" + std::to_string(i),
               MakeProceduralTexture(kind, s, size)});
    }
  }
  return set;
}

void TextureSet::AddPhotos(const std::string& folder, int size, int stride, int phase,
                           int max_files) {
  namespace fs = std::filesystem;
  if (!fs::is_directory(folder)) ThrowInput("--textures: {} is not a folder", folder);
  std::vector<std::string> files;
  for (const auto& entry : fs::directory_iterator(folder)) {
    std::string ext = entry.path().extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return std::tolower(c); });
    if (entry.is_regular_file() && (ext == ".png" || ext == ".jpg" || ext == ".jpeg")) {
      files.push_back(entry.path().string());
    }
  }
  std::sort(files.begin(), files.end());
  int added = 0;
  for (size_t i = static_cast<size_t>(phase); i < files.size() && added < max_files;
       i += static_cast<size_t>(stride)) {
    cv::Mat bgr = cv::imread(files[i], cv::IMREAD_COLOR);
    if (bgr.empty()) continue;
    const int side = std::min(bgr.cols, bgr.rows);
    cv::Mat crop = bgr(cv::Rect((bgr.cols - side) / 2, (bgr.rows - side) / 2, side, side));
    cv::Mat rgb;
    cv::resize(crop, rgb, cv::Size(size, size), 0, 0, cv::INTER_AREA);
    cv::cvtColor(rgb, rgb, cv::COLOR_BGR2RGB);
    // Photographs do not tile; as posters and facades they are shown once per face, and as other
    // surfaces they are mirrored into a seamless tile.
    cv::Mat tile;
    cv::Mat half;
    cv::resize(rgb, half, cv::Size(size / 2, size / 2), 0, 0, cv::INTER_AREA);
    cv::Mat top, bottom, flipped_x, flipped_y, flipped_xy;
    cv::flip(half, flipped_x, 1);
    cv::flip(half, flipped_y, 0);
    cv::flip(half, flipped_xy, -1);
    cv::hconcat(half, flipped_x, top);
    cv::hconcat(flipped_y, flipped_xy, bottom);
    cv::vconcat(top, bottom, tile);
    // Not walls: office walls are painted (procedural, moderate texture); photographs appear as
    // posters, facades, floors and clothing.
    const TextureKind kinds[] = {TextureKind::kPoster, TextureKind::kFacade, TextureKind::kClothing,
                                 TextureKind::kFloor, TextureKind::kClothing};
    const TextureKind use = kinds[added % 5];
    const bool once = use == TextureKind::kPoster || use == TextureKind::kFacade;
    Add({use, files[i], once ? rgb : tile});
    if (use != TextureKind::kPoster) Add({TextureKind::kPoster, files[i], rgb});
    ++added;
  }
  if (added == 0) ThrowInput("--textures: no readable .png/.jpg image in {}", folder);
}

const std::vector<int>& TextureSet::OfKind(TextureKind kind) const {
  return by_kind_[static_cast<size_t>(kind)];
}

void TextureSet::Add(Texture texture) {
  by_kind_[static_cast<size_t>(texture.kind)].push_back(static_cast<int>(textures_.size()));
  textures_.push_back(std::move(texture));
}

cv::Mat MakeFabricTexture(int size) {
  // Plain cloth: soft folds (low-frequency noise stretched along the garment) and a faint weave,
  // between 0.8 and 1 so that it only shades the garment's colour.
  Rng rng(0xFAB1C, 1);
  const cv::Mat folds = Fractal(rng, size, 4, 3, 0.5f);
  const cv::Mat weave = Fractal(rng, size, std::min(size, 64), 2, 0.5f);
  cv::Mat out(size, size, CV_8UC3);
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) {
      const float f = folds.at<float>(y, x), w = weave.at<float>(y, x);
      const float v = 0.8f + 0.16f * f + 0.04f * w;
      out.at<cv::Vec3b>(y, x) = cv::Vec3b::all(cv::saturate_cast<uchar>(255.0f * v));
    }
  }
  return out;
}

}  // namespace moslam::synth
