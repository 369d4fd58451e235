#include "moslam/semantic/model_card.h"

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <set>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "moslam/semantic/input_limits.h"
#include "moslam/util/error.h"
#include "moslam/util/strings.h"
#include "moslam/util/yaml.h"

namespace moslam::semantic {
namespace fs = std::filesystem;
namespace {

std::string ResolvePath(const std::string& value, const std::string& key, const ModelCard& card,
                        const std::string& shared_root) {
  const fs::path given(value);
  std::error_code ec;
  if (given.is_absolute()) {
    if (!fs::exists(given, ec))
      ThrowInFile(card.path, fmt::format("{}: {} does not exist", key, Excerpt(value, 400)));
    return value;
  }
  const fs::path beside = fs::path(card.path).parent_path() / given;
  if (fs::exists(beside, ec)) return beside.string();
  const fs::path shared = fs::path(shared_root) / given;
  if (fs::exists(shared, ec)) return shared.string();
  ThrowInFile(card.path, fmt::format("{}: '{}' found neither at {} nor at {} (set MOSLAM_SHARED "
                                     "to the folder that holds models/)",
                                     key, Excerpt(value, 400), Excerpt(beside.string(), 400),
                                     Excerpt(shared.string(), 400)));
}

void CheckClassNames(const ModelCard& card) {
  std::set<std::string> seen;
  for (const std::string& name : card.classes) {
    if (name.empty()) ThrowInFile(card.path, "classes: a class name is empty");
    if (!seen.insert(name).second) {
      ThrowInFile(card.path, fmt::format("classes: '{}' is listed twice", Excerpt(name)));
    }
  }
}

void CheckInputSize(const ModelCard& card) {
  const int w = card.input_width;
  const int h = card.input_height;
  if (w < kMinCardInputSide || h < kMinCardInputSide || w > kMaxCardInputSide ||
      h > kMaxCardInputSide) {
    ThrowInFile(card.path, fmt::format("input_width, input_height: {}x{}, each must be in [{}, {}] "
                                       "pixels",
                                       w, h, kMinCardInputSide, kMaxCardInputSide));
  }
  if (!card.config.empty() && (w % kDarknetInputMultiple != 0 || h % kDarknetInputMultiple != 0)) {
    ThrowInFile(card.path, fmt::format("input_width, input_height: {}x{}, a Darknet network needs "
                                       "multiples of {}",
                                       w, h, kDarknetInputMultiple));
  }
}

}  // namespace

const char* ToString(ModelKind kind) {
  switch (kind) {
    case ModelKind::kSegmentation:
      return "segmentation";
    case ModelKind::kDetector:
      return "detector";
    case ModelKind::kTorch:
      return "torch";
  }
  return "?";
}

std::string SharedRoot() {
  const char* env = std::getenv("MOSLAM_SHARED");
  return env != nullptr && *env != '\0' ? std::string(env) : std::string("../shared");
}

void ModelCard::Check() const {
  // A torch card's model file says what the card leaves out (net::CompleteTorchCard).
  const bool torch = kind == ModelKind::kTorch;
  const bool size_from_model = torch && input_width == 0 && input_height == 0;
  if (!size_from_model) CheckInputSize(*this);
  if (mean.size() != 3) ThrowInFile(path, "mean: give 3 numbers, one per channel");
  if (!(scale > 0.0)) ThrowInFile(path, fmt::format("scale: must be > 0, got {}", scale));
  const bool classes_from_model = torch && classes.empty();
  if (kind != ModelKind::kDetector && !classes_from_model &&
      (classes.size() < 2 || classes.size() > 255)) {
    ThrowInFile(path, fmt::format("classes: a segmentation model needs 2 to 255 classes, got {}",
                                  classes.size()));
  }
  if (classes.empty() && !classes_from_model) ThrowInFile(path, "classes: no class listed");
  CheckClassNames(*this);
  if (movable.empty() && !torch) ThrowInFile(path, "movable: no movable class listed");
  for (const std::string& name : classes_from_model ? std::vector<std::string>() : movable) {
    if (std::find(classes.begin(), classes.end(), name) == classes.end()) {
      ThrowInFile(path, fmt::format("movable: '{}' is not one of the classes", Excerpt(name)));
    }
  }
  if (!background.empty() && BackgroundIndex() < 0) {
    ThrowInFile(path,
                fmt::format("background: '{}' is not one of the classes", Excerpt(background)));
  }
  if (!(confidence > 0.0f && confidence < 1.0f)) ThrowInFile(path, "confidence: must be in (0, 1)");
  if (!(nms > 0.0f && nms <= 1.0f)) ThrowInFile(path, "nms: must be in (0, 1]");
  if (threads < 1 || threads > 64) ThrowInFile(path, "threads: must be in 1..64");
  if (!(box_probability > 0.5f && box_probability < 1.0f)) {
    // Above one half so that a box's class wins the argmax inside the box without the CRF.
    ThrowInFile(path, "box_probability: must be in (0.5, 1)");
  }
  try {
    refine.Check();
  } catch (const InputError& e) {
    ThrowInFile(path, e.what());
  }
}

std::vector<bool> ModelCard::MovableFlags() const {
  std::vector<bool> flags(classes.size(), false);
  for (size_t i = 0; i < classes.size(); ++i) {
    flags[i] = std::find(movable.begin(), movable.end(), classes[i]) != movable.end();
  }
  return flags;
}

int ModelCard::BackgroundIndex() const {
  if (background.empty()) return -1;
  const auto it = std::find(classes.begin(), classes.end(), background);
  return it == classes.end() ? -1 : static_cast<int>(it - classes.begin());
}

ModelCard LoadModelCard(const std::string& path, const std::string& shared_root) {
  YamlFile file(path);
  ModelCard card;
  card.path = path;
  card.name = fs::path(path).stem().string();
  file.Read("name", &card.name);
  const std::string type = file.Required<std::string>("type");
  if (type == "segmentation") {
    card.kind = ModelKind::kSegmentation;
  } else if (type == "detector") {
    card.kind = ModelKind::kDetector;
  } else if (type == "torch") {
    card.kind = ModelKind::kTorch;
  } else {
    ThrowInFile(
        path, fmt::format("type: '{}' is none of segmentation, detector and torch", Excerpt(type)));
  }
  card.model = ResolvePath(file.Required<std::string>("model"), "model", card, shared_root);
  std::string config;
  if (file.Read("config", &config) && !config.empty()) {
    card.config = ResolvePath(config, "config", card, shared_root);
  }
  if (card.kind == ModelKind::kTorch) {
    // Optional: the model file holds them (net::CompleteTorchCard checks the given ones). The
    // networks take RGB in [-1, 1] (net/networks.h), so that is what an absent mean/scale means.
    card.mean = {127.5, 127.5, 127.5};
    card.scale = 1.0 / 127.5;
    file.Read("input_width", &card.input_width);
    file.Read("input_height", &card.input_height);
    file.Read("classes", &card.classes);
    file.Read("movable", &card.movable);
  } else {
    card.input_width = file.Required<int>("input_width");
    card.input_height = file.Required<int>("input_height");
    card.classes = file.Required<std::vector<std::string>>("classes");
    card.movable = file.Required<std::vector<std::string>>("movable");
  }
  file.Read("mean", &card.mean);
  file.Read("scale", &card.scale);
  file.Read("rgb", &card.rgb);
  file.Read("background", &card.background);
  file.Read("confidence", &card.confidence);
  file.Read("nms", &card.nms);
  file.Read("box_probability", &card.box_probability);
  file.Read("threads", &card.threads);
  ReadRefineOptions(file, "refine.", &card.refine);
  file.RejectUnread();
  card.Check();
  return card;
}

void SetMovable(const std::vector<std::string>& names, ModelCard* card) {
  for (const std::string& name : names) {
    if (std::find(card->classes.begin(), card->classes.end(), name) == card->classes.end()) {
      ThrowInFile(card->path, fmt::format("--movable: '{}' is not one of the model's classes ({})",
                                          name, fmt::join(card->classes, ", ")));
    }
  }
  card->movable = names;
  card->Check();
}

}  // namespace moslam::semantic
