#include "moslam/net/model_file.h"

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <unistd.h>

#include "moslam/util/crc32.h"
#include "moslam/util/error.h"
#include "moslam/util/strings.h"

namespace moslam::net {
namespace {

// Archive layout (a TorchScript module holding attributes only):
//   format  "moslam-net"        version  int
//   kind    "classifier" | "segmenter"
//   config  NetConfig JSON text
//   weights Dict[str, Tensor]   parameter and buffer names as torch::nn::Module names them
//   checksum int                version 2 on: Checksum() of kind, config and weights
//   optimizer (sub-archive), trainer_state (JSON text): checkpoints only
// Weights live in a dictionary because attribute names of an archive must be identifiers, and
// module paths contain dots.
//
// Version 2 added the checksum: libtorch's zip reader does not verify the CRC-32s of its
// records, so a file with flipped bytes in its tensors loaded and ran, and a damaged network
// gave masks that made tracking fail on every frame. Version 1 files (no checksum) still load.
constexpr const char* kFormat = "moslam-net";
constexpr int64_t kVersion = 2;
constexpr int64_t kFirstVersionWithChecksum = 2;

std::string KindName(NetKind kind) {
  return kind == NetKind::kClassifier ? "classifier" : "segmenter";
}

c10::Dict<std::string, at::Tensor> Weights(torch::nn::Module& net, bool half) {
  c10::Dict<std::string, at::Tensor> weights;
  auto add = [&](const std::string& name, const torch::Tensor& t) {
    // On the CPU, so that a model trained on a GPU loads anywhere.
    torch::Tensor value = t.detach().to(torch::kCPU).clone();
    if (half && value.is_floating_point()) value = value.to(torch::kFloat16);
    weights.insert(name, value);
  };
  for (const auto& p : net.named_parameters()) add(p.key(), p.value());
  for (const auto& b : net.named_buffers()) add(b.key(), b.value());
  return weights;
}

// CRC-32 of what a model file says about its network: kind, config text, and every tensor's
// name, type, shape and bytes, in name order (the dictionary's own order is not part of the
// format).
int64_t Checksum(const std::string& kind, const std::string& config,
                 const c10::Dict<std::string, at::Tensor>& weights) {
  auto add_text = [](const std::string& text, uint32_t crc) {
    return Crc32(text.data(), text.size() + 1, crc);  // with the terminator: "ab","c" != "a","bc"
  };
  uint32_t crc = add_text(config, add_text(kind, 0));
  std::vector<std::string> names;
  for (const auto& entry : weights) names.push_back(entry.key());
  std::sort(names.begin(), names.end());
  for (const std::string& name : names) {
    const at::Tensor tensor = weights.at(name).contiguous();
    crc = add_text(name, crc);
    crc = add_text(std::string(c10::toString(tensor.scalar_type())), crc);
    const std::vector<int64_t> sizes = tensor.sizes().vec();
    crc = Crc32(sizes.data(), sizes.size() * sizeof(int64_t), crc);
    crc = Crc32(tensor.data_ptr(), tensor.numel() * tensor.element_size(), crc);
  }
  return static_cast<int64_t>(crc);
}

void WriteModel(torch::serialize::OutputArchive& archive, torch::nn::Module& net,
                const NetConfig& config, bool half) {
  const std::string kind = KindName(config.kind);
  const std::string config_text = ToJson(config).dump();
  const c10::Dict<std::string, at::Tensor> weights = Weights(net, half);
  archive.write("format", c10::IValue(std::string(kFormat)));
  archive.write("version", c10::IValue(kVersion));
  archive.write("kind", c10::IValue(kind));
  archive.write("config", c10::IValue(config_text));
  archive.write("weights", c10::IValue(weights));
  archive.write("checksum", c10::IValue(Checksum(kind, config_text, weights)));
}

// Writes to a temporary file beside `path` and renames it: readers never see a partial file.
void SaveAtomically(torch::serialize::OutputArchive& archive, const std::string& path) {
  const std::string temp = fmt::format("{}.tmp{}", path, ::getpid());
  try {
    archive.save_to(temp);
  } catch (const c10::Error& e) {
    std::filesystem::remove(temp);
    ThrowInFile(path, fmt::format("cannot write model file: {}", e.what_without_backtrace()));
  }
  std::error_code error;
  std::filesystem::rename(temp, path, error);
  if (error) {
    std::filesystem::remove(temp);
    ThrowInFile(path, fmt::format("cannot rename {} to it: {}", temp, error.message()));
  }
}

// Opens the archive and returns its format version.
int64_t Open(const std::string& path, torch::serialize::InputArchive& archive) {
  if (std::filesystem::is_directory(path)) ThrowInFile(path, "is a directory, not a model file");
  if (!std::filesystem::is_regular_file(path)) ThrowInFile(path, "model file not found");
  try {
    archive.load_from(path);
  } catch (const c10::Error& e) {
    ThrowInFile(path, fmt::format("not a model file (or a damaged one): {}",
                                  Excerpt(e.what_without_backtrace(), 400)));
  }
  c10::IValue format;
  if (!archive.try_read("format", format) || !format.isString() ||
      format.toStringRef() != kFormat) {
    ThrowInFile(path, "not a moslam model file (no format tag)");
  }
  c10::IValue version;
  if (!archive.try_read("version", version) || !version.isInt() || version.toInt() < 1 ||
      version.toInt() > kVersion) {
    ThrowInFile(path,
                fmt::format("model file format version {} (this build reads 1 to {})",
                            version.isInt() ? std::to_string(version.toInt()) : "?", kVersion));
  }
  return version.toInt();
}

std::string ReadString(torch::serialize::InputArchive& archive, const std::string& key,
                       const std::string& path) {
  c10::IValue value;
  if (!archive.try_read(key, value) || !value.isString()) {
    ThrowInFile(path, fmt::format("model file lacks '{}'", key));
  }
  return value.toStringRef();
}

NetConfig ReadConfig(torch::serialize::InputArchive& archive, const std::string& path) {
  const std::string text = ReadString(archive, "config", path);
  try {
    return NetConfigFromJson(nlohmann::json::parse(text));
  } catch (const nlohmann::json::exception& e) {
    ThrowInFile(path, fmt::format("bad config JSON: {}", Excerpt(e.what(), 400)));
  } catch (const InputError& e) {
    ThrowInFile(path, e.what());
  }
}

// Throws InputError naming the file unless its stored checksum matches what it holds (files of
// version 2 on; version 1 had none).
void VerifyChecksum(torch::serialize::InputArchive& archive, int64_t version,
                    const c10::Dict<std::string, at::Tensor>& weights, const std::string& path) {
  if (version < kFirstVersionWithChecksum) return;
  c10::IValue stored;
  if (!archive.try_read("checksum", stored) || !stored.isInt()) {
    ThrowInFile(path, fmt::format("model file of version {} lacks its 'checksum'", version));
  }
  const int64_t actual =
      Checksum(ReadString(archive, "kind", path), ReadString(archive, "config", path), weights);
  if (actual != stored.toInt()) {
    ThrowInFile(path, fmt::format("model file is damaged: its contents have CRC-32 {:08x}, it was "
                                  "written with {:08x}",
                                  actual, stored.toInt()));
  }
}

// Copies the stored weights into `net` (float32 or whatever its tensors are), checking the
// file's checksum and that every tensor is present with the right shape.
void ReadWeights(torch::serialize::InputArchive& archive, int64_t version, torch::nn::Module& net,
                 const std::string& path) {
  c10::IValue value;
  if (!archive.try_read("weights", value) || !value.isGenericDict()) {
    ThrowInFile(path, "model file lacks 'weights'");
  }
  const c10::Dict<std::string, at::Tensor> weights =
      c10::impl::toTypedDict<std::string, at::Tensor>(value.toGenericDict());
  VerifyChecksum(archive, version, weights, path);
  torch::NoGradGuard no_grad;
  auto load = [&](const std::string& name, torch::Tensor& target) {
    const auto it = weights.find(name);
    if (it == weights.end()) ThrowInFile(path, fmt::format("no tensor '{}'", name));
    const at::Tensor& stored = it->value();
    if (stored.sizes() != target.sizes()) {
      ThrowInFile(path,
                  fmt::format("tensor '{}' has shape {}, the network expects {}", name,
                              fmt::join(stored.sizes(), "x"), fmt::join(target.sizes(), "x")));
    }
    target.copy_(stored);
  };
  for (auto& p : net.named_parameters()) load(p.key(), p.value());
  for (auto& b : net.named_buffers()) load(b.key(), b.value());
  if (weights.size() != net.named_parameters().size() + net.named_buffers().size()) {
    ThrowInFile(path, fmt::format("model file has {} tensors, the network {}", weights.size(),
                                  net.named_parameters().size() + net.named_buffers().size()));
  }
}

template <typename Net>
Net LoadNet(const std::string& path, NetKind kind) {
  torch::serialize::InputArchive archive;
  const int64_t version = Open(path, archive);
  const std::string stored_kind = ReadString(archive, "kind", path);
  if (stored_kind != KindName(kind)) {
    ThrowInFile(path, fmt::format("is a {} model file, not a {}", stored_kind, KindName(kind)));
  }
  const NetConfig config = ReadConfig(archive, path);
  Net net(config);
  ReadWeights(archive, version, *net, path);
  net->backbone()->ApplyFreezing();
  return net;
}

template <typename Net>
void SaveNet(const std::string& path, Net& net, bool half) {
  torch::serialize::OutputArchive archive;
  WriteModel(archive, *net, net->config(), half);
  SaveAtomically(archive, path);
}

}  // namespace

void SaveClassifier(const std::string& path, ClassifierNet& net, bool half) {
  SaveNet(path, net, half);
}

void SaveSegmenter(const std::string& path, SegmenterNet& net, bool half) {
  SaveNet(path, net, half);
}

ClassifierNet LoadClassifier(const std::string& path) {
  return LoadNet<ClassifierNet>(path, NetKind::kClassifier);
}

SegmenterNet LoadSegmenter(const std::string& path) {
  return LoadNet<SegmenterNet>(path, NetKind::kSegmenter);
}

NetConfig ReadNetConfig(const std::string& path) {
  torch::serialize::InputArchive archive;
  Open(path, archive);
  return ReadConfig(archive, path);
}

void SaveCheckpoint(const std::string& path, torch::nn::Module& net, const NetConfig& config,
                    torch::optim::Optimizer& optimizer, const nlohmann::json& trainer_state) {
  torch::serialize::OutputArchive archive;
  WriteModel(archive, net, config, false);
  torch::serialize::OutputArchive optimizer_archive;
  optimizer.save(optimizer_archive);
  archive.write("optimizer", optimizer_archive);
  archive.write("trainer_state", c10::IValue(trainer_state.dump()));
  SaveAtomically(archive, path);
}

nlohmann::json LoadCheckpoint(const std::string& path, torch::nn::Module& net,
                              torch::optim::Optimizer& optimizer) {
  torch::serialize::InputArchive archive;
  const int64_t version = Open(path, archive);
  ReadWeights(archive, version, net, path);
  torch::serialize::InputArchive optimizer_archive;
  if (!archive.try_read("optimizer", optimizer_archive)) {
    ThrowInFile(path, "not a checkpoint (no optimizer state)");
  }
  try {
    optimizer.load(optimizer_archive);
  } catch (const c10::Error& e) {
    ThrowInFile(path, fmt::format("optimizer state does not fit: {}", e.what_without_backtrace()));
  }
  const std::string state = ReadString(archive, "trainer_state", path);
  try {
    return nlohmann::json::parse(state);
  } catch (const nlohmann::json::exception& e) {
    ThrowInFile(path, fmt::format("bad trainer_state JSON: {}", Excerpt(e.what(), 400)));
  }
}

}  // namespace moslam::net
