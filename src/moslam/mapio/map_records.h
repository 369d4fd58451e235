// Internal to mapio: the records of a map file's body (docs/MAP_FORMAT.md), written from and read
// into map::Map. Reading validates every count, index and id against what was read before, so a
// file that passed its checksum but is inconsistent (written by a broken writer) is an InputError
// naming the record, never an out-of-range access.
#pragma once

#include <memory>

#include "moslam/map/map.h"
#include "moslam/mapio/map_archive.h"

namespace moslam::mapio::internal {

// A keyframe's immutable part: id, timestamp, pose, features, bag of words.
void WriteKeyFrame(const map::KeyFrame& keyframe, Writer* out);
std::shared_ptr<map::KeyFrame> ReadKeyFrame(Reader* in, map::Map* map);

// A map point with its observations; its reference keyframe must be in `map` (written as the
// first observing keyframe when the reference is gone).
void WritePoint(const map::MapPoint& point, const map::Map& map, Writer* out);
void ReadPoint(Reader* in, map::Map* map);

// A keyframe's mutable graph: its keypoints' map points, covisibility weights, spanning-tree
// parent. Only links to keyframes and points in the map are written.
void WriteGraph(const map::KeyFrame& keyframe, const map::Map& map, Writer* out);
void ReadGraph(Reader* in, map::Map* map);

}  // namespace moslam::mapio::internal
