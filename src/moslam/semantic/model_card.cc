#include "moslam/semantic/model_card.h"

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <set>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "moslam/util/error.h"
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
      ThrowInFile(card.path, fmt::format("{}: {} does not exist", key, value));
    return value;
  }
  const fs::path beside = fs::path(card.path).parent_path() / given;
  if (fs::exists(beside, ec)) return beside.string();
  const fs::path shared = fs::path(shared_root) / given;
  if (fs::exists(shared, ec)) return shared.string();
  ThrowInFile(card.path, fmt::format("{}: '{}' found neither at {} nor at {} (set MOSLAM_SHARED "
                                     "to the folder that holds models/)",
                                     key, value, beside.string(), shared.string()));
}

void CheckClassNames(const ModelCard& card) {
  std::set<std::string> seen;
  for (const std::string& name : card.classes) {
    if (name.empty()) ThrowInFile(card.path, "classes: a class name is empty");
    if (!seen.insert(name).second) {
      ThrowInFile(card.path, fmt::format("classes: '{}' is listed twice", name));
    }
  }
}

}  // namespace

const char* ToString(ModelKind kind) {
  return kind == ModelKind::kSegmentation ? "segmentation" : "detector";
}

std::string SharedRoot() {
  const char* env = std::getenv("MOSLAM_SHARED");
  return env != nullptr && *env != '\0' ? std::string(env) : std::string("../shared");
}

void ModelCard::Check() const {
  if (input_width <= 0 || input_height <= 0) {
    ThrowInFile(path, fmt::format("input_width, input_height: must be > 0, got {}x{}", input_width,
                                  input_height));
  }
  if (mean.size() != 3) ThrowInFile(path, "mean: give 3 numbers, one per channel");
  if (!(scale > 0.0)) ThrowInFile(path, fmt::format("scale: must be > 0, got {}", scale));
  if (kind == ModelKind::kSegmentation && (classes.size() < 2 || classes.size() > 255)) {
    ThrowInFile(path, fmt::format("classes: a segmentation model needs 2 to 255 classes, got {}",
                                  classes.size()));
  }
  if (classes.empty()) ThrowInFile(path, "classes: no class listed");
  CheckClassNames(*this);
  if (movable.empty()) ThrowInFile(path, "movable: no movable class listed");
  for (const std::string& name : movable) {
    if (std::find(classes.begin(), classes.end(), name) == classes.end()) {
      ThrowInFile(path, fmt::format("movable: '{}' is not one of the classes", name));
    }
  }
  if (!background.empty() && BackgroundIndex() < 0) {
    ThrowInFile(path, fmt::format("background: '{}' is not one of the classes", background));
  }
  if (!(confidence > 0.0f && confidence < 1.0f)) ThrowInFile(path, "confidence: must be in (0, 1)");
  if (!(nms > 0.0f && nms <= 1.0f)) ThrowInFile(path, "nms: must be in (0, 1]");
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
  } else {
    ThrowInFile(path, fmt::format("type: '{}' is neither segmentation nor detector", type));
  }
  card.model = ResolvePath(file.Required<std::string>("model"), "model", card, shared_root);
  std::string config;
  if (file.Read("config", &config) && !config.empty()) {
    card.config = ResolvePath(config, "config", card, shared_root);
  }
  card.input_width = file.Required<int>("input_width");
  card.input_height = file.Required<int>("input_height");
  file.Read("mean", &card.mean);
  file.Read("scale", &card.scale);
  file.Read("rgb", &card.rgb);
  card.classes = file.Required<std::vector<std::string>>("classes");
  card.movable = file.Required<std::vector<std::string>>("movable");
  file.Read("background", &card.background);
  file.Read("confidence", &card.confidence);
  file.Read("nms", &card.nms);
  file.Read("box_probability", &card.box_probability);
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
