// Checks of the training options and the data sources (training.h).
#include <fmt/format.h>

#include "moslam/util/error.h"
#include "moslam/weak/training.h"

namespace moslam::weak {

void DataSource::Check() const {
  const int sources = !list.empty() + !camvid.empty() + !synthetic.empty();
  if (sources != 1) {
    throw InputError(
        "training data: give exactly one of an image list (--list with --classes), a CamVid "
        "root (--camvid) or a synthetic training folder (--synthetic)");
  }
  if (!list.empty() && classes.empty()) {
    throw InputError("training data: --list " + list + " needs --classes (a classes file)");
  }
  if (!camvid.empty() && split.empty()) throw InputError("training data: empty CamVid --split");
  if (synthetic_crop_labels && synthetic.empty()) {
    throw InputError(
        "training data: --synthetic-crop-labels needs a synthetic folder (--synthetic)");
  }
}

ImageList DataSource::Load() const {
  Check();
  ImageList loaded;
  if (!camvid.empty()) {
    loaded = ReadCamVid(camvid, split);
  } else if (!synthetic.empty()) {
    loaded = ReadSyntheticTraining(synthetic, synthetic_crop_labels);
  } else {
    loaded = ReadImageList(list, ReadClassesFile(classes));
  }
  return keep_classes.empty() ? loaded : KeepClasses(loaded, keep_classes);
}

std::vector<std::string> SegmenterClasses(const ImageList& list) {
  std::vector<std::string> classes = list.class_names;
  if (!list.background.empty()) classes.push_back(list.background);
  return classes;
}

void CommonTrainOptions::Check() const {
  data.Check();
  auto positive = [](double value, const char* name) {
    if (!(value > 0)) throw InputError(fmt::format("training option {} must be > 0", name));
  };
  if (out.empty()) throw InputError("training: an output folder (--out) is required");
  positive(epochs, "epochs");
  positive(batch_size, "batch_size");
  positive(learning_rate, "learning_rate");
  if (backbone_lr_factor < 0) throw InputError("training option backbone_lr_factor must be >= 0");
  if (weight_decay < 0) throw InputError("training option weight_decay must be >= 0");
  positive(threads, "threads");
  if (max_images < 0) throw InputError("training option max_images must be >= 0");
  if (preview_images < 0) throw InputError("training option preview_images must be >= 0");
  augment.Check();
}

}  // namespace moslam::weak
