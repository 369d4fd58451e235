#include "moslam/mapio/map_file.h"

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <set>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "moslam/mapio/map_archive.h"
#include "moslam/mapio/map_records.h"
#include "moslam/util/atomic_file.h"
#include "moslam/util/check.h"
#include "moslam/util/crc32.h"
#include "moslam/util/error.h"

namespace moslam::mapio {
namespace {

using internal::Reader;
using internal::Writer;

// Fixed little-endian prefix: magic (8), version (u32), CRC-32 of the body (u32), body size
// (u64); the body follows.
constexpr size_t kPrefixBytes = kMapPrefixBytes;

void PutLittleEndian(uint64_t v, int bytes, std::string* out) {
  for (int k = 0; k < bytes; ++k) out->push_back(static_cast<char>((v >> (8 * k)) & 0xffu));
}

uint64_t GetLittleEndian(const std::string& s, size_t at, int bytes) {
  uint64_t v = 0;
  for (int k = 0; k < bytes; ++k)
    v |= static_cast<uint64_t>(static_cast<uint8_t>(s[at + k])) << (8 * k);
  return v;
}

void WriteIdentity(const MapIdentity& id, Writer* out) {
  out->Value(id.sensor);
  for (double c : id.camera) out->Value(c);
  out->Value(id.orb_levels);
  out->Value(id.orb_scale_factor);
  out->Value(id.vocabulary_words);
  out->Value(id.vocabulary_checksum);
}

MapIdentity ReadIdentity(Reader* in) {
  in->SetRecord("identity");
  MapIdentity id;
  id.sensor = in->Value<int32_t>();
  for (double& c : id.camera) c = in->Value<double>();
  id.orb_levels = in->Value<int32_t>();
  id.orb_scale_factor = in->Value<double>();
  id.vocabulary_words = in->Value<uint64_t>();
  id.vocabulary_checksum = in->Value<uint32_t>();
  return id;
}

std::string SensorName(int32_t sensor) {
  if (sensor < 0 || sensor > static_cast<int32_t>(io::SensorType::kRgbD)) {
    return "unknown sensor " + std::to_string(sensor);
  }
  return io::ToString(static_cast<io::SensorType>(sensor));
}

// Each mismatch its own message: the user's fix differs (another settings file, another
// vocabulary, another sensor).
void CheckIdentity(const MapIdentity& found, const MapIdentity& expected, const std::string& path) {
  if (found.sensor != expected.sensor) {
    throw InputError(fmt::format("{}: map made for sensor {}, this run's is {}", path,
                                 SensorName(found.sensor), SensorName(expected.sensor)));
  }
  static const char* const kNames[] = {"fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3", "bf"};
  for (size_t k = 0; k < found.camera.size(); ++k) {
    if (found.camera[k] != expected.camera[k]) {
      throw InputError(
          fmt::format("{}: map made with another camera ({} {} in the map, {} in "
                      "this run's settings)",
                      path, kNames[k], found.camera[k], expected.camera[k]));
    }
  }
  if (found.orb_levels != expected.orb_levels ||
      found.orb_scale_factor != expected.orb_scale_factor) {
    throw InputError(
        fmt::format("{}: map made with another ORB pyramid (ORBextractor.nLevels {}, scaleFactor "
                    "{} in the map; "
                    "{} and {} in this run's settings)",
                    path, found.orb_levels, found.orb_scale_factor, expected.orb_levels,
                    expected.orb_scale_factor));
  }
  if (found.vocabulary_words != expected.vocabulary_words ||
      found.vocabulary_checksum != expected.vocabulary_checksum) {
    throw InputError(fmt::format(
        "{}: map made with another vocabulary ({} words, checksum {:08x}; this run's: {} words, "
        "checksum {:08x})",
        path, found.vocabulary_words, found.vocabulary_checksum, expected.vocabulary_words,
        expected.vocabulary_checksum));
  }
}

// A spanning tree that loops would send every walk up the tree round forever.
void CheckTree(const map::Map& map, Reader* in) {
  in->SetRecord("spanning tree");
  std::set<uint64_t> rooted;  // keyframes whose chain reaches a root
  for (const auto& [id, kf] : map.keyframes()) {
    std::set<uint64_t> chain;
    for (auto k = kf; k && !rooted.count(k->id); k = k->parent()) {
      if (!chain.insert(k->id).second)
        in->Fail("a cycle through keyframe " + std::to_string(k->id));
    }
    rooted.insert(chain.begin(), chain.end());
  }
}

}  // namespace

uint32_t VocabularyChecksum(const vocab::Vocabulary& vocabulary) {
  std::string bytes;
  PutLittleEndian(static_cast<uint64_t>(vocabulary.k()), 4, &bytes);
  PutLittleEndian(static_cast<uint64_t>(vocabulary.levels()), 4, &bytes);
  uint32_t crc = Crc32(bytes.data(), bytes.size());
  std::vector<uint8_t> chunk;
  chunk.reserve(40 * 4096);
  for (size_t w = 0; w < vocabulary.size(); ++w) {
    const uint8_t* d = vocabulary.WordDescriptor(static_cast<vocab::WordId>(w));
    chunk.insert(chunk.end(), d, d + 32);
    const double weight = vocabulary.Weight(static_cast<vocab::WordId>(w));
    uint64_t bits = 0;
    std::memcpy(&bits, &weight, sizeof bits);
    for (int k = 0; k < 8; ++k) chunk.push_back(static_cast<uint8_t>((bits >> (8 * k)) & 0xffu));
    if (chunk.size() >= 40 * 4096) {
      crc = Crc32(chunk.data(), chunk.size(), crc);
      chunk.clear();
    }
  }
  return Crc32(chunk.data(), chunk.size(), crc);
}

MapIdentity MakeIdentity(io::SensorType sensor, const io::OrbSlamSettings& settings, double bf,
                         const vocab::Vocabulary* vocabulary) {
  MapIdentity id;
  id.sensor = static_cast<int32_t>(sensor);
  const auto& c = settings.camera;
  const auto& d = c.distortion;
  id.camera = {c.fx, c.fy, c.cx, c.cy, d.k1, d.k2, d.p1, d.p2, d.k3, bf};
  id.orb_levels = settings.orb.num_levels;
  id.orb_scale_factor = settings.orb.scale_factor;
  if (vocabulary && !vocabulary->empty()) {
    id.vocabulary_words = vocabulary->size();
    id.vocabulary_checksum = VocabularyChecksum(*vocabulary);
  }
  return id;
}

std::string SerializeMap(const map::Map& map, const MapIdentity& identity) {
  Writer body;
  WriteIdentity(identity, &body);
  body.Value(map.next_keyframe_id());
  body.Value(map.next_point_id());
  body.Value(map.generation());
  body.Value(static_cast<uint64_t>(map.keyframes().size()));
  for (const auto& [id, kf] : map.keyframes()) internal::WriteKeyFrame(*kf, &body);
  body.Value(static_cast<uint64_t>(map.points().size()));
  for (const auto& [id, p] : map.points()) internal::WritePoint(*p, map, &body);
  for (const auto& [id, kf] : map.keyframes()) internal::WriteGraph(*kf, map, &body);
  std::vector<uint64_t> loops;  // each undirected edge once, smaller id first
  for (const auto& [a, b] : map.loop_edges()) {
    if (a < b && map.keyframe(a) && map.keyframe(b)) loops.insert(loops.end(), {a, b});
  }
  body.Vector(loops);
  return SealMapBody(body.Bytes());
}

std::string SealMapBody(const std::string& body) {
  std::string out(kMapMagic, sizeof kMapMagic);
  PutLittleEndian(kMapFormatVersion, 4, &out);
  PutLittleEndian(Crc32(body.data(), body.size()), 4, &out);
  PutLittleEndian(body.size(), 8, &out);
  static_assert(sizeof kMapMagic + 4 + 4 + 8 == kPrefixBytes);
  return out + body;
}

void SaveMap(const map::Map& map, const MapIdentity& identity, const std::string& path) {
  std::string bytes;
  {
    std::lock_guard<std::mutex> lock(map.mutex());
    bytes = SerializeMap(map, identity);
  }
  WriteFileAtomically(path, bytes, "map");
}

void ParseMap(const std::string& bytes, const std::string& path, const MapIdentity& expected,
              map::Map* into) {
  MOSLAM_CHECK(into->keyframes().empty() && into->points().empty())
      << "ParseMap into a non-empty map";
  if (bytes.size() < sizeof kMapMagic ||
      std::memcmp(bytes.data(), kMapMagic, sizeof kMapMagic) != 0) {
    throw InputError(path + ": not a moslam map file (no MOSLAMAP magic at byte 0)");
  }
  if (bytes.size() < kPrefixBytes) {
    throw InputError(fmt::format("{}: truncated in the header ({} of {} bytes)", path, bytes.size(),
                                 kPrefixBytes));
  }
  const auto version = static_cast<uint32_t>(GetLittleEndian(bytes, 8, 4));
  if (version != kMapFormatVersion) {
    throw InputError(fmt::format("{}: map format version {}, this build reads version {}", path,
                                 version, kMapFormatVersion));
  }
  const auto crc = static_cast<uint32_t>(GetLittleEndian(bytes, 12, 4));
  const uint64_t size = GetLittleEndian(bytes, 16, 8);
  const uint64_t have = bytes.size() - kPrefixBytes;
  if (size != have) {
    throw InputError(fmt::format("{}: {} (the header says a body of {} bytes, the file has {})",
                                 path, have < size ? "truncated" : "trailing bytes after the body",
                                 size, have));
  }
  const uint32_t actual = Crc32(bytes.data() + kPrefixBytes, size);
  if (actual != crc) {
    throw InputError(fmt::format(
        "{}: checksum mismatch (body CRC-32 {:08x}, header says {:08x}): the file is corrupted",
        path, actual, crc));
  }
  if (size == 0) throw InputError(path + ": empty body");
  Reader in(path, bytes.data() + kPrefixBytes, size, kPrefixBytes);
  CheckIdentity(ReadIdentity(&in), expected, path);
  in.SetRecord("counters");
  const auto next_keyframe_id = in.Value<uint64_t>();
  const auto next_point_id = in.Value<uint64_t>();
  const auto generation = in.Value<uint64_t>();
  const auto num_keyframes = in.Value<uint64_t>();
  for (uint64_t k = 0; k < num_keyframes; ++k) internal::ReadKeyFrame(&in, into);
  in.SetRecord("counters");
  const auto num_points = in.Value<uint64_t>();
  for (uint64_t k = 0; k < num_points; ++k) internal::ReadPoint(&in, into);
  for (uint64_t k = 0; k < num_keyframes; ++k) internal::ReadGraph(&in, into);
  CheckTree(*into, &in);
  in.SetRecord("loop edges");
  const auto loops = in.Vector<uint64_t>();
  if (loops.size() % 2 != 0) in.Fail("an odd number of loop-edge ids");
  for (size_t k = 0; k < loops.size(); k += 2) {
    if (loops[k] >= loops[k + 1] || !into->keyframe(loops[k]) || !into->keyframe(loops[k + 1])) {
      in.Fail("a loop edge between keyframes not in the map");
    }
    into->AddLoopEdge(loops[k], loops[k + 1]);
  }
  if (in.left() != 0) in.Fail(std::to_string(in.left()) + " bytes left over after the last record");
  if (next_keyframe_id < into->next_keyframe_id() || next_point_id < into->next_point_id()) {
    in.Fail("id counters below the ids in the map");
  }
  into->RestoreCounters(next_keyframe_id, next_point_id, generation);
}

void LoadMap(const std::string& path, const MapIdentity& expected, map::Map* into) {
  if (std::filesystem::is_directory(path))
    throw InputError(path + ": is a directory, not a map file");
  std::ifstream file(path, std::ios::binary | std::ios::ate);
  if (!file) throw InputError(path + ": cannot open the map file");
  const std::streamoff size = file.tellg();
  if (size < 0) throw InputError(path + ": cannot read the map file");
  std::string bytes(static_cast<size_t>(size), '\0');
  file.seekg(0);
  if (!file.read(bytes.data(), size)) throw InputError(path + ": cannot read the map file");
  std::lock_guard<std::mutex> lock(into->mutex());
  ParseMap(bytes, path, expected, into);
}

MapIdentity ReadMapIdentity(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) throw InputError(path + ": cannot open the map file");
  // The identity is the body's first record; a few hundred bytes hold it.
  std::string bytes(kPrefixBytes + 4096, '\0');
  file.read(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  bytes.resize(static_cast<size_t>(file.gcount()));
  if (bytes.size() <= kPrefixBytes || std::memcmp(bytes.data(), kMapMagic, sizeof kMapMagic) != 0) {
    throw InputError(path + ": not a moslam map file (no MOSLAMAP magic at byte 0)");
  }
  Reader in(path, bytes.data() + kPrefixBytes, bytes.size() - kPrefixBytes, kPrefixBytes);
  return ReadIdentity(&in);
}

MapFileStats StatsOf(const map::Map& map, size_t bytes) {
  MapFileStats stats;
  stats.bytes = bytes;
  stats.keyframes = map.keyframes().size();
  stats.points = map.points().size();
  for (const auto& [id, kf] : map.keyframes()) {
    for (const auto& [other, w] : kf->connection_weights()) stats.covisibility_edges += other > id;
  }
  stats.loop_edges = map.loop_edges().size() / 2;
  return stats;
}

}  // namespace moslam::mapio
