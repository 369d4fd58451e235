// Textures for synthetic scenes: a built-in procedural set (works with no external files) and
// photographs from a folder.
//
// ORB (Rublee et al., ICCV 2011) finds corners at 8 pyramid levels, so every texture carries detail
// at several scales: fractal value noise over 5-6 octaves plus structure (bricks, weave, print
// motifs, window grids). Textures tile seamlessly so that large surfaces can repeat them.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace moslam::synth {

// What a texture is for; scenes pick textures of the right kind.
enum class TextureKind {
  kWall,      // plaster, wallpaper
  kFloor,     // carpet, wood planks, tiles
  kCeiling,   // acoustic tiles
  kWood,      // furniture
  kPoster,    // pictures on walls, screen contents
  kClothing,  // shirts, jackets (plaid, stripes, prints)
  kTrousers,  // denim, cloth
  kSkin,      // faces, hands
  kHair,
  kCarPaint,
  kRoad,
  kFacade,
  kCount
};

struct Texture {
  TextureKind kind = TextureKind::kWall;
  std::string name;  // "procedural:<kind>:<n>" or the photograph's path
  cv::Mat rgb;       // CV_8UC3, RGB order (as OpenGL takes it), square, power-of-two size
};

class TextureSet {
 public:
  // The procedural textures: `per_kind` of every kind, generated from `seed`. size: pixels (power
  // of two, >= 64).
  static TextureSet Procedural(uint64_t seed, int per_kind, int size);

  // Adds photographs from `folder` (*.png, *.jpg, *.jpeg, sorted by name so that the order is
  // deterministic), centre-cropped to a square and resized to `size`; each is used as a poster,
  // and (tinted) as wall, floor, facade and clothing variety. `stride`/`phase` select every
  // stride-th file starting at phase (the training mode uses files the presets do not).
  // Throws InputError when the folder does not exist or holds no image.
  void AddPhotos(const std::string& folder, int size, int stride = 1, int phase = 0,
                 int max_files = 64);

  const std::vector<Texture>& textures() const { return textures_; }
  // Indices of the textures of a kind (never empty for a procedural set).
  const std::vector<int>& OfKind(TextureKind kind) const;

 private:
  void Add(Texture texture);
  std::vector<Texture> textures_;
  std::vector<std::vector<int>> by_kind_ =
      std::vector<std::vector<int>>(static_cast<size_t>(TextureKind::kCount));
};

// Plain cloth for garments without a pattern: grey folds and weave in [0.8, 1] that the garment's
// colour multiplies (the renderer's texture -2 for meshes).
cv::Mat MakeFabricTexture(int size);

// One procedural texture (exposed for tests).
cv::Mat MakeProceduralTexture(TextureKind kind, uint64_t seed, int size);

}  // namespace moslam::synth
