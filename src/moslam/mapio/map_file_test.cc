// Map files: a round trip gives the same bytes and the same map, and every kind of bad file gives
// its own InputError naming the file.
#include "moslam/mapio/map_file.h"

#include <fstream>
#include <functional>
#include <limits>
#include <sstream>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "moslam/mapio/test_map.h"
#include "moslam/testing/error_of.h"
#include "moslam/testing/shared_data.h"

namespace moslam::mapio {
namespace {

using moslam::testing::ErrorOf;

MapIdentity Identity() {
  MapIdentity id;
  id.sensor = static_cast<int32_t>(io::SensorType::kRgbD);
  id.camera = {525.0, 525.0, 319.5, 239.5, 0.0, 0.0, 0.0, 0.0, 0.0, 40.0};
  id.orb_levels = 8;
  id.orb_scale_factor = 1.2;
  id.vocabulary_words = 10000;
  id.vocabulary_checksum = 0x12345678u;
  return id;
}

std::string Serialized(const map::Map& map) {
  std::lock_guard<std::mutex> lock(map.mutex());
  return SerializeMap(map, Identity());
}

std::string ReadAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// Parses `bytes` as if read from "bad.map" and returns the error.
std::string ParseError(const std::string& bytes, const MapIdentity& identity = Identity()) {
  return ErrorOf([&] {
    map::Map map;
    ParseMap(bytes, "bad.map", identity, &map);
  });
}

// The body replaced and the header's size and CRC made to match: what a broken writer (not a
// damaged file) would produce, for the consistency checks behind the checksum.
std::string Resealed(const std::string& bytes) {
  return SealMapBody(bytes.substr(kMapPrefixBytes));
}

class MapFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    testing::BuildTestMap(12, 300, 7, &map_);
    bytes_ = Serialized(map_);
  }
  map::Map map_;
  std::string bytes_;
};

TEST_F(MapFileTest, SaveLoadSaveIsByteIdentical) {
  moslam::testing::TempDir dir;
  const std::string path = dir.path() + "/a.map";
  SaveMap(map_, Identity(), path);
  EXPECT_EQ(ReadAll(path), bytes_);
  map::Map loaded;
  LoadMap(path, Identity(), &loaded);
  const std::string again = dir.path() + "/b.map";
  SaveMap(loaded, Identity(), again);
  EXPECT_EQ(ReadAll(again), bytes_);
  EXPECT_FALSE(std::ifstream(path + ".tmp").good());  // the temporary was renamed
}

TEST_F(MapFileTest, LoadedMapHoldsTheSameKeyFramesPointsAndEdges) {
  map::Map loaded;
  ParseMap(bytes_, "a.map", Identity(), &loaded);
  ASSERT_EQ(loaded.keyframes().size(), map_.keyframes().size());
  ASSERT_EQ(loaded.points().size(), map_.points().size());
  EXPECT_EQ(loaded.next_keyframe_id(), map_.next_keyframe_id());
  EXPECT_EQ(loaded.next_point_id(), map_.next_point_id());
  EXPECT_EQ(loaded.loop_edges(), map_.loop_edges());
  EXPECT_EQ(loaded.keyframes().count(2), 0u);  // the erased keyframe stays erased
  for (const auto& [id, a] : map_.keyframes()) {
    const auto b = loaded.keyframe(id);
    ASSERT_NE(b, nullptr) << id;
    EXPECT_EQ(b->T_cam_world().rotation().coeffs(), a->T_cam_world().rotation().coeffs());
    EXPECT_EQ(b->T_cam_world().translation(), a->T_cam_world().translation());
    ASSERT_EQ(b->frame.size(), a->frame.size());
    EXPECT_EQ(cv::norm(b->frame.descriptors, a->frame.descriptors, cv::NORM_L1), 0.0);
    for (size_t i = 0; i < a->frame.size(); ++i) {
      EXPECT_EQ(b->frame.keypoints[i].pt, a->frame.keypoints[i].pt);
      EXPECT_EQ(b->frame.keypoints_undistorted[i].octave, a->frame.keypoints_undistorted[i].octave);
      EXPECT_EQ(b->frame.depth[i], a->frame.depth[i]);
      EXPECT_EQ(b->points[i] ? b->points[i]->id : 0, a->points[i] ? a->points[i]->id : 0);
    }
    EXPECT_EQ(b->frame.near_movable, a->frame.near_movable);
    EXPECT_EQ(b->bow, a->bow);
    EXPECT_EQ(b->bow_features, a->bow_features);
    EXPECT_EQ(b->connection_weights(), a->connection_weights());
    EXPECT_EQ(b->children(), a->children());
    EXPECT_EQ(b->parent() ? b->parent()->id : 999, a->parent() ? a->parent()->id : 999);
    // The grid is rebuilt: the same radius search.
    EXPECT_EQ(b->frame.FeaturesInArea(320, 240, 50), a->frame.FeaturesInArea(320, 240, 50));
    // Best covisibles in the same order (rebuilt from the weights).
    const auto ba = a->BestCovisibles(-1), bb = b->BestCovisibles(-1);
    ASSERT_EQ(bb.size(), ba.size());
    for (size_t k = 0; k < ba.size(); ++k) EXPECT_EQ(bb[k]->id, ba[k]->id);
  }
  for (const auto& [id, a] : map_.points()) {
    const auto& b = loaded.points().at(id);
    EXPECT_EQ(b->position, a->position);
    EXPECT_EQ(b->normal, a->normal);
    EXPECT_EQ(b->max_distance, a->max_distance);
    EXPECT_EQ(cv::norm(b->descriptor, a->descriptor, cv::NORM_L1), 0.0);
    EXPECT_EQ(b->reference.lock()->id, a->reference.lock()->id);
    EXPECT_EQ(b->num_observations(), a->num_observations());
    EXPECT_EQ(b->visible, a->visible);
    EXPECT_EQ(b->found, a->found);
    ASSERT_EQ(b->observations().size(), a->observations().size());
    for (const auto& [kf_id, obs] : a->observations()) EXPECT_EQ(b->IndexIn(kf_id), obs.index);
  }
}

TEST_F(MapFileTest, EmptyMapRoundTrips) {
  map::Map empty, loaded;
  const std::string bytes = Serialized(empty);
  ParseMap(bytes, "e.map", Identity(), &loaded);
  EXPECT_TRUE(loaded.keyframes().empty());
  EXPECT_EQ(Serialized(loaded), bytes);
}

TEST_F(MapFileTest, WrongMagic) {
  std::string bad = bytes_;
  bad[0] = 'X';
  const std::string e = ParseError(bad);
  EXPECT_NE(e.find("bad.map"), std::string::npos) << e;
  EXPECT_NE(e.find("not a moslam map file"), std::string::npos) << e;
  EXPECT_NE(ParseError("").find("not a moslam map file"), std::string::npos);
}

TEST_F(MapFileTest, OtherVersion) {
  std::string bad = bytes_;
  bad[8] = static_cast<char>(kMapFormatVersion + 1);
  const std::string e = ParseError(bad);
  EXPECT_NE(e.find("bad.map: map format version 2, this build reads version 1"), std::string::npos)
      << e;
}

TEST_F(MapFileTest, TruncatedAnywhere) {
  // In the header, right after it, in the first keyframe, half-way, one byte short.
  for (size_t size : {size_t{12}, size_t{24}, size_t{200}, bytes_.size() / 2, bytes_.size() - 1}) {
    const std::string e = ParseError(bytes_.substr(0, size));
    EXPECT_NE(e.find("bad.map: truncated"), std::string::npos) << size << ": " << e;
  }
  const std::string e = ParseError(bytes_ + "x");
  EXPECT_NE(e.find("bad.map: trailing bytes"), std::string::npos) << e;
}

TEST_F(MapFileTest, FlippedBytesFailTheChecksum) {
  for (size_t at : {size_t{24}, size_t{30}, bytes_.size() / 3, bytes_.size() - 1}) {
    std::string bad = bytes_;
    bad[at] = static_cast<char>(bad[at] ^ 0x10);
    const std::string e = ParseError(bad);
    EXPECT_NE(e.find("bad.map: checksum mismatch"), std::string::npos) << at << ": " << e;
  }
}

TEST_F(MapFileTest, WrongVocabularyCameraOrSensor) {
  MapIdentity other = Identity();
  other.vocabulary_checksum ^= 1;
  std::string e = ParseError(bytes_, other);
  EXPECT_NE(e.find("bad.map: map made with another vocabulary"), std::string::npos) << e;
  other = Identity();
  other.vocabulary_words = 0;
  e = ParseError(bytes_, other);
  EXPECT_NE(e.find("another vocabulary"), std::string::npos) << e;
  other = Identity();
  other.camera[0] = 520.0;
  e = ParseError(bytes_, other);
  EXPECT_NE(e.find("bad.map: map made with another camera (fx 525 in the map, 520"),
            std::string::npos)
      << e;
  other = Identity();
  other.orb_levels = 4;
  e = ParseError(bytes_, other);
  EXPECT_NE(e.find("bad.map: map made with another ORB pyramid (ORBextractor.nLevels 8"),
            std::string::npos)
      << e;
  other = Identity();
  other.sensor = static_cast<int32_t>(io::SensorType::kStereo);
  e = ParseError(bytes_, other);
  EXPECT_NE(e.find("bad.map: map made for sensor rgbd, this run's is stereo"), std::string::npos)
      << e;
}

TEST_F(MapFileTest, InconsistentBodyBehindAGoodChecksum) {
  // Every byte of the body after the identity set to 0xff in turn (counts, ids, lengths become
  // huge): an error naming the file and a byte offset, never a crash or a huge allocation.
  const size_t body_start = 24 + 1 + 4 + 80 + 4 + 8 + 8 + 4;  // prefix, endianness, identity
  for (size_t at = body_start; at < body_start + 400; at += 7) {
    std::string bad = bytes_;
    bad[at] = static_cast<char>(0xff);
    bad = Resealed(bad);
    if (bad == Resealed(bytes_)) continue;
    map::Map map;
    try {
      ParseMap(bad, "bad.map", Identity(), &map);
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()).rfind("bad.map: ", 0), 0u) << e.what();
    }
  }
  // A reference to a keyframe not in the map: the loop edge's last id.
  std::string bad = bytes_;
  bad[bad.size() - 8] = static_cast<char>(0x7f);
  const std::string e = ParseError(Resealed(bad));
  EXPECT_NE(e.find("bad.map: a loop edge between keyframes not in the map at byte"),
            std::string::npos)
      << e;
}

// Values a writer never produces, behind a good checksum: each an error naming the file, where
// before (the map fuzzer's finding, fuzz/regressions/map/) infinite image bounds reached the
// keypoint grid, which cast a NaN cell to int.
TEST_F(MapFileTest, NonFiniteValuesAreRefused) {
  const auto edited = [](const std::function<void(feature::Frame*)>& frame,
                         const std::function<void(map::Map*)>& points = {}) {
    map::Map map;
    testing::BuildTestMap(3, 40, 7, &map, frame);
    if (points) points(&map);
    return ParseError(Serialized(map));
  };
  const float inf = std::numeric_limits<float>::infinity();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THAT(edited([&](feature::Frame* f) { f->bounds.min_y = -inf; }),
              ::testing::HasSubstr("bad.map: empty or non-finite image bounds"));
  EXPECT_THAT(edited([&](feature::Frame* f) { f->keypoints[3].angle = nan; }),
              ::testing::HasSubstr("non-finite position, size, angle or response"));
  EXPECT_THAT(edited([&](feature::Frame* f) { f->depth[2] = nan; }),
              ::testing::HasSubstr("non-finite keypoint depth"));
  EXPECT_THAT(edited([&](feature::Frame* f) { f->scale_factors[1] = 0.0f; }),
              ::testing::HasSubstr("scale pyramid value"));
  EXPECT_THAT(edited({}, [&](map::Map* m) { m->points().begin()->second->max_distance = nan; }),
              ::testing::HasSubstr("scale-invariance range"));
}

TEST_F(MapFileTest, MissingFileAndDirectory) {
  moslam::testing::TempDir dir;
  EXPECT_NE(ErrorOf([&] {
              map::Map m;
              LoadMap(dir.path() + "/none.map", Identity(), &m);
            }).find("none.map: cannot open the map file"),
            std::string::npos);
  EXPECT_NE(ErrorOf([&] {
              map::Map m;
              LoadMap(dir.path(), Identity(), &m);
            }).find("is a directory"),
            std::string::npos);
  EXPECT_NE(ErrorOf([&] {
              SaveMap(map_, Identity(), dir.path() + "/no/such/dir/a.map");
            }).find("cannot write the map"),
            std::string::npos);
}

}  // namespace
}  // namespace moslam::mapio
