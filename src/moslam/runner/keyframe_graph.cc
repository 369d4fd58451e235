#include "moslam/runner/keyframe_graph.h"

#include <fstream>

#include <nlohmann/json.hpp>

#include "moslam/util/atomic_file.h"
#include "moslam/util/error.h"

namespace moslam::runner {
namespace {

constexpr const char* kFormat = "moslam keyframe graph";
constexpr int kVersion = 1;

// `flat` (`width` numbers per edge) as a JSON array of edges; `one_way`: only i < j.
nlohmann::json Edges(const std::vector<uint32_t>& flat, size_t width, bool one_way) {
  nlohmann::json out = nlohmann::json::array();
  for (size_t k = 0; k + width <= flat.size(); k += width) {
    if (one_way && flat[k] >= flat[k + 1]) continue;
    out.push_back(std::vector<uint32_t>(flat.begin() + k, flat.begin() + k + width));
  }
  return out;
}

// The edges of `json[key]` back into a flat array, each index checked against `n` keyframes;
// `both_ways`: each covisibility edge is added in both directions, as a view holds it.
std::vector<uint32_t> FlatEdges(const nlohmann::json& json, const char* key, size_t width, size_t n,
                                bool both_ways, const std::string& path) {
  const auto edges = json.find(key);
  if (edges == json.end() || !edges->is_array()) ThrowInFile(path, fmt::format("no \"{}\"", key));
  std::vector<uint32_t> out;
  for (const nlohmann::json& edge : *edges) {
    if (!edge.is_array() || edge.size() != width) {
      ThrowInFile(path, fmt::format("\"{}\": {} is not {} numbers", key, edge.dump(), width));
    }
    const std::vector<int64_t> v = edge.get<std::vector<int64_t>>();
    for (size_t k = 0; k < 2; ++k) {
      if (v[k] < 0 || static_cast<size_t>(v[k]) >= n) {
        ThrowInFile(path, fmt::format("\"{}\": keyframe {} of {}", key, v[k], n));
      }
    }
    for (int64_t x : v) out.push_back(static_cast<uint32_t>(x));
    if (both_ways) out.insert(out.end(), {out[out.size() - 2], out[out.size() - 3], out.back()});
  }
  return out;
}

}  // namespace

std::optional<KeyFrameGraph> FinalKeyFrameGraph(Tracker& tracker,
                                                const eval::Trajectory& keyframes) {
  slam::ViewRequest request;
  request.graph = true;
  slam::SystemView view;
  if (!tracker.View(&view, request) || view.keyframes.size() != keyframes.size()) {
    return std::nullopt;
  }
  KeyFrameGraph graph;
  graph.timestamps = keyframes.timestamps;
  graph.covisibility = std::move(view.covisibility);
  graph.spanning_tree = std::move(view.spanning_tree);
  graph.loops = std::move(view.loops);
  return graph;
}

void WriteKeyFrameGraph(const KeyFrameGraph& graph, const std::string& path) {
  const nlohmann::json json = {{"format", kFormat},
                               {"version", kVersion},
                               {"min_covisibility_weight", slam::kViewCovisibilityMinWeight},
                               {"timestamps", graph.timestamps},
                               {"covisibility", Edges(graph.covisibility, 3, true)},
                               {"spanning_tree", Edges(graph.spanning_tree, 2, false)},
                               {"loops", Edges(graph.loops, 2, false)}};
  WriteFileAtomically(path, json.dump() + "\n", "keyframe graph");
}

KeyFrameGraph ReadKeyFrameGraph(const std::string& path) {
  std::ifstream in(path);
  if (!in) ThrowInFile(path, "cannot be read");
  const nlohmann::json json = nlohmann::json::parse(in, nullptr, false);
  if (json.is_discarded() || !json.is_object() || json.value("format", "") != kFormat) {
    ThrowInFile(path, "not a keyframe graph (keyframe_graph.json of `moslam run`)");
  }
  KeyFrameGraph graph;
  try {
    if (json.at("version").get<int>() != kVersion) {
      ThrowInFile(path, fmt::format("version {}, this moslam reads {}", json.at("version").dump(),
                                    kVersion));
    }
    graph.timestamps = json.at("timestamps").get<std::vector<double>>();
    const size_t n = graph.timestamps.size();
    graph.covisibility = FlatEdges(json, "covisibility", 3, n, true, path);
    graph.spanning_tree = FlatEdges(json, "spanning_tree", 2, n, false, path);
    graph.loops = FlatEdges(json, "loops", 2, n, false, path);
  } catch (const nlohmann::json::exception& e) {
    ThrowInFile(path, e.what());  // a missing key or a value of the wrong type
  }
  return graph;
}

}  // namespace moslam::runner
