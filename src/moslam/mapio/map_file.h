// Map files (docs/MAP_FORMAT.md): the whole map of a run (keyframes with their features, poses
// and bag-of-words vectors; map points with their observations; covisibility graph, spanning tree
// and loop edges) in a versioned binary file with a CRC-32 of its body, and what the map was made
// with (sensor, camera, vocabulary) so that it is only ever loaded into a system that can use it.
//
//   mapio::MapIdentity identity = mapio::MakeIdentity(sensor, settings, bf, &vocabulary);
//   mapio::SaveMap(map, identity, "office.map");        // map mutex taken inside
//   map::Map loaded;
//   mapio::LoadMap("office.map", identity, &loaded);    // InputError on any bad file
//
// Output is deterministic: save, load and save again gives the same bytes. Every failure to load
// is an InputError naming the file and what is wrong (wrong magic, another format version,
// truncated, checksum mismatch, a malformed record and its byte offset, another sensor, camera or
// vocabulary); nothing in a file can crash the reader.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>

#include "moslam/camera/pinhole_camera.h"
#include "moslam/io/orbslam_settings.h"
#include "moslam/io/sequence.h"
#include "moslam/map/map.h"
#include "moslam/vocab/vocabulary.h"

namespace moslam::mapio {

// "MOSLAMAP" then the version; a change of the body's layout bumps the version.
inline constexpr char kMapMagic[8] = {'M', 'O', 'S', 'L', 'A', 'M', 'A', 'P'};
inline constexpr uint32_t kMapFormatVersion = 1;
// The fixed prefix before the body: magic, version (4 bytes), CRC-32 of the body (4), body size
// (8), little-endian.
inline constexpr size_t kMapPrefixBytes = 24;

// What a map was made with. A map is loaded only where all of it matches: keyframe descriptors
// and bag-of-words vectors mean nothing under another vocabulary, poses and depths nothing under
// another camera.
struct MapIdentity {
  int32_t sensor = 0;  // io::SensorType as an integer
  // fx, fy, cx, cy, k1, k2, p1, p2, k3 (pixels, distortion coefficients), bf (pixel-metres).
  std::array<double, 10> camera{};
  // The ORB pyramid (ORBextractor.nLevels, scaleFactor): keypoint octaves and the points' scale
  // ranges are in its levels.
  int32_t orb_levels = 0;
  double orb_scale_factor = 0.0;
  // The vocabulary's number of words and the CRC-32 of its words' descriptors and weights
  // (VocabularyChecksum): the same tree whatever file format it was loaded from. 0 words: none.
  uint64_t vocabulary_words = 0;
  uint32_t vocabulary_checksum = 0;
};

// CRC-32 of k, levels and every word's descriptor and IDF weight, in word order.
uint32_t VocabularyChecksum(const vocab::Vocabulary& vocabulary);
// `bf`: the one the system uses (0 for monocular). `vocabulary` may be null (no vocabulary).
MapIdentity MakeIdentity(io::SensorType sensor, const io::OrbSlamSettings& settings, double bf,
                         const vocab::Vocabulary* vocabulary);

// The map's bytes (header and body). Hold map.mutex() while calling.
std::string SerializeMap(const map::Map& map, const MapIdentity& identity);
// A map file's bytes from its body: the prefix (magic, version, CRC-32, size) put in front. For
// tests and fuzzers that change a body and need a file whose checksum matches it.
std::string SealMapBody(const std::string& body);
// Writes SerializeMap to `path` through a temporary file in the same folder, renamed over `path`
// when complete, so a crash never leaves half a map. Takes map.mutex() itself. InputError when
// the file cannot be written.
void SaveMap(const map::Map& map, const MapIdentity& identity, const std::string& path);

// Parses `bytes` (read from `path`, named in every error) into `into`, which must be empty
// (CHECK). `expected`: the identity of the system that will use the map; a sensor, camera or
// vocabulary that differs is an InputError. Hold into->mutex() or own `into` alone.
void ParseMap(const std::string& bytes, const std::string& path, const MapIdentity& expected,
              map::Map* into);
// Reads `path` and ParseMap's it; takes into->mutex() itself.
void LoadMap(const std::string& path, const MapIdentity& expected, map::Map* into);
// The identity a map file says it was made with, for readers that use no camera or vocabulary
// of their own (`moslam view` draws the points and keyframes): LoadMap(path, ReadMapIdentity(path),
// ...) then loads any good file. InputError as LoadMap for a file too short or not a map.
MapIdentity ReadMapIdentity(const std::string& path);

// Per-file facts for logs and reports: counts of what the body holds.
struct MapFileStats {
  size_t bytes = 0;
  size_t keyframes = 0;
  size_t points = 0;
  size_t covisibility_edges = 0;  // each undirected edge once
  size_t loop_edges = 0;          // each undirected edge once
};
MapFileStats StatsOf(const map::Map& map, size_t bytes);

}  // namespace moslam::mapio
