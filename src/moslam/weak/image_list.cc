#include "moslam/weak/image_list.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>
#include <opencv2/imgcodecs.hpp>

#include "moslam/io/class_list.h"
#include "moslam/util/check.h"
#include "moslam/util/error.h"
#include "moslam/util/strings.h"
#include "moslam/util/text_file.h"

namespace moslam::weak {
namespace {

namespace fs = std::filesystem;

constexpr const char* kBackgroundName = "background";

// CamVid's 11 classes in id order (Brostow et al. 2009, as in the SegNet split); id 11 is
// "unlabelled" and never a class.
const std::vector<std::string>& CamVidClassNames() {
  static const std::vector<std::string> names = {"Sky",      "Building",   "Pole",       "Road",
                                                 "Pavement", "Tree",       "SignSymbol", "Fence",
                                                 "Car",      "Pedestrian", "Bicyclist"};
  return names;
}

bool IsCamVidMovable(const std::string& name) {
  return name == "Car" || name == "Pedestrian" || name == "Bicyclist";
}

// `image` resolved against the list's folder: absolute paths are kept.
std::string ResolvePath(const fs::path& folder, const std::string& image) {
  const fs::path p(image);
  if (p.is_absolute()) return p.lexically_normal().string();
  return (folder / p).lexically_normal().string();
}

// `image` as it is written into a list in `folder`: relative when below it, else absolute.
std::string PathForList(const fs::path& folder, const std::string& image) {
  const fs::path absolute_image = fs::absolute(image).lexically_normal();
  const fs::path absolute_folder = fs::absolute(folder).lexically_normal();
  const fs::path relative = absolute_image.lexically_relative(absolute_folder);
  if (relative.empty() || *relative.begin() == "..") return absolute_image.string();
  return relative.string();
}

std::string JoinNames(const ImageList& list) {
  return fmt::format("{}", fmt::join(list.class_names, ", "));
}

void CheckEntry(const ImageList& list, const ImageListEntry& entry) {
  for (const int c : entry.classes) {
    MOSLAM_CHECK(c >= 0 && c < list.num_classes())
        << "class index " << c << " of " << entry.image << " out of range";
  }
}

cv::Mat ReadIdImage(const std::string& path) {
  cv::Mat ids = cv::imread(path, cv::IMREAD_UNCHANGED);
  if (ids.empty()) ThrowInFile(path, "cannot be read as a label image");
  if (ids.type() != CV_8UC1) ThrowInFile(path, "a label image must be 8-bit single-channel");
  return ids;
}

bool IsImageFile(const fs::path& p) {
  const std::string ext = ToLower(p.extension().string());
  return ext == ".png" || ext == ".jpg" || ext == ".jpeg";
}

}  // namespace

int ImageList::ClassIndex(const std::string& name) const {
  const auto it = std::find(class_names.begin(), class_names.end(), name);
  return it == class_names.end() ? -1 : static_cast<int>(it - class_names.begin());
}

ImageList ReadClassesFile(const std::string& path) {
  ImageList list;
  int expected_id = 0;
  for (const io::ClassInfo& info : io::ReadClassList(path)) {
    if (info.id != expected_id) {
      ThrowAtLine(path, info.line,
                  fmt::format("class ids must be 0, 1, 2, ... in order; expected {}, got {}",
                              expected_id, info.id));
    }
    ++expected_id;
    if (info.name == kBackgroundName) {
      // "None of the others": a segmentation label, never an image-level one.
      list.background = info.name;
      continue;
    }
    list.class_names.push_back(info.name);
    list.movable.push_back(info.movable);
  }
  if (list.class_names.empty()) ThrowInFile(path, "lists no classes (other than background)");
  return list;
}

void WriteClassesFile(const std::string& path, const ImageList& list) {
  MOSLAM_CHECK(list.movable.size() == list.class_names.size());
  std::ofstream out(path);
  if (!out) ThrowInFile(path, "cannot be opened for writing");
  out << "# id name movable\n";
  int id = 0;
  if (!list.background.empty()) out << id++ << " " << list.background << " 0\n";
  for (int c = 0; c < list.num_classes(); ++c) {
    out << id++ << " " << list.class_names[c] << " " << (list.movable[c] ? 1 : 0) << "\n";
  }
  out.close();
  if (out.fail()) ThrowInFile(path, "write failed");
}

ImageList ReadImageList(const std::string& path, ImageList classes) {
  RequireFile(path, "image list");
  const fs::path folder = fs::path(path).parent_path();
  ImageList list = std::move(classes);
  list.entries.clear();
  for (const TextLine& line : ReadDataLines(path)) {
    const auto fields = SplitFields(line.text);
    ImageListEntry entry;
    entry.image = ResolvePath(folder, std::string(fields[0]));
    std::error_code ec;
    if (!fs::is_regular_file(entry.image, ec)) {
      ThrowAtLine(path, line.number,
                  fmt::format("image '{}' does not exist (looked for {})", Excerpt(fields[0]),
                              Excerpt(entry.image, 400)));
    }
    for (size_t i = 1; i < fields.size(); ++i) {
      if (fields[i].front() == '#') break;  // trailing comment
      const std::string name(fields[i]);
      if (!list.background.empty() && name == list.background) continue;
      const int c = list.ClassIndex(name);
      if (c < 0) {
        ThrowAtLine(
            path, line.number,
            fmt::format("unknown class '{}' (classes: {})", Excerpt(name), JoinNames(list)));
      }
      entry.classes.push_back(c);
    }
    std::sort(entry.classes.begin(), entry.classes.end());
    entry.classes.erase(std::unique(entry.classes.begin(), entry.classes.end()),
                        entry.classes.end());
    list.entries.push_back(std::move(entry));
  }
  return list;
}

void WriteImageList(const std::string& path, const ImageList& list) {
  const fs::path folder = fs::path(path).parent_path();
  std::ofstream out(path);
  if (!out) ThrowInFile(path, "cannot be opened for writing");
  out << "# image-level labels: <image> <class> <class> ... (classes: " << JoinNames(list) << ")\n";
  for (const ImageListEntry& entry : list.entries) {
    CheckEntry(list, entry);
    out << PathForList(folder, entry.image);
    for (const int c : entry.classes) out << " " << list.class_names[c];
    out << "\n";
  }
  out.close();
  if (out.fail()) ThrowInFile(path, "write failed");
}

ImageList SplitHoldout(const ImageList& list, int every, bool holdout) {
  if (every < 2) ThrowInput("SplitHoldout: every must be >= 2, got {}", every);
  ImageList part = list;
  part.entries.clear();
  for (size_t i = 0; i < list.entries.size(); ++i) {
    const bool held_out = (i + 1) % static_cast<size_t>(every) == 0;
    if (held_out == holdout) part.entries.push_back(list.entries[i]);
  }
  return part;
}

std::vector<int> CropLabels(const cv::Mat& label_ids, const cv::Rect& roi, int num_classes,
                            double min_fraction) {
  MOSLAM_CHECK(label_ids.type() == CV_8UC1) << "label image must be CV_8UC1";
  MOSLAM_CHECK(num_classes > 0 && num_classes <= 256);
  MOSLAM_CHECK(roi.area() > 0 && (roi & cv::Rect(0, 0, label_ids.cols, label_ids.rows)) == roi)
      << "roi " << roi << " outside the " << label_ids.cols << "x" << label_ids.rows << " image";
  std::vector<long> counts(256, 0);
  for (int y = roi.y; y < roi.y + roi.height; ++y) {
    const uint8_t* row = label_ids.ptr<uint8_t>(y);
    for (int x = roi.x; x < roi.x + roi.width; ++x) ++counts[row[x]];
  }
  // A pixel count, so that a class covering exactly min_fraction is present despite rounding
  // (0.001 * 10000 is not exactly 10 in floating point); at least one pixel in any case.
  const double area = static_cast<double>(roi.area());
  const long needed = std::max(1L, static_cast<long>(std::ceil(min_fraction * area - 1e-6)));
  std::vector<int> present;
  for (int c = 0; c < num_classes; ++c) {
    if (counts[c] >= needed) present.push_back(c);
  }
  return present;
}

cv::Rect GridCell(const cv::Rect& area, int r, int c, int rows, int cols) {
  MOSLAM_CHECK(rows >= 1 && cols >= 1 && r >= 0 && r < rows && c >= 0 && c < cols)
      << "cell (" << r << ", " << c << ") of a " << cols << "x" << rows << " grid";
  const int x0 = area.x + c * area.width / cols;
  const int x1 = area.x + (c + 1) * area.width / cols;
  const int y0 = area.y + r * area.height / rows;
  const int y1 = area.y + (r + 1) * area.height / rows;
  return cv::Rect(x0, y0, x1 - x0, y1 - y0);
}

ImageList ReadCamVid(const std::string& root, const std::string& split, double min_fraction) {
  if (!(min_fraction >= 0.0 && min_fraction < 1.0)) {
    ThrowInput("ReadCamVid: min_fraction must be in [0, 1), got {}", min_fraction);
  }
  const fs::path images_dir = fs::path(root) / split;
  const fs::path labels_dir = fs::path(root) / (split + "annot");
  RequireDirectory(images_dir.string(), "CamVid image folder");
  RequireDirectory(labels_dir.string(), "CamVid label folder");
  ImageList list;
  list.class_names = CamVidClassNames();
  for (const std::string& name : list.class_names) list.movable.push_back(IsCamVidMovable(name));
  list.label_min_fraction = min_fraction;

  std::vector<fs::path> images;
  for (const auto& item : fs::directory_iterator(images_dir)) {
    if (item.is_regular_file() && IsImageFile(item.path())) images.push_back(item.path());
  }
  std::sort(images.begin(), images.end());
  if (images.empty()) ThrowInFile(images_dir.string(), "holds no images (.png, .jpg)");
  for (const fs::path& image : images) {
    ImageListEntry entry;
    entry.image = image.string();
    entry.label_image = (labels_dir / image.stem()).string() + ".png";
    std::error_code ec;
    if (!fs::is_regular_file(entry.label_image, ec)) {
      ThrowInFile(entry.label_image, "label image of " + entry.image + " does not exist");
    }
    const cv::Mat ids = ReadIdImage(entry.label_image);
    entry.classes =
        CropLabels(ids, cv::Rect(0, 0, ids.cols, ids.rows), list.num_classes(), min_fraction);
    list.entries.push_back(std::move(entry));
  }
  spdlog::info("CamVid {}: {} images from {}", split, list.entries.size(), images_dir.string());
  return list;
}

ImageList ReadSyntheticTraining(const std::string& folder, bool crop_labels) {
  RequireDirectory(folder, "synthetic training folder");
  const ImageList classes = ReadClassesFile((fs::path(folder) / "classes.txt").string());
  ImageList list = ReadImageList((fs::path(folder) / "labels.txt").string(), classes);
  if (!crop_labels) return list;
  // Class ids in the generator's images are classes.txt's: background first when there is one.
  const int offset = list.background.empty() ? 0 : 1;
  list.label_to_class.assign(list.class_names.size() + offset, -1);
  for (int c = 0; c < list.num_classes(); ++c) list.label_to_class[c + offset] = c;
  list.label_min_fraction = kSyntheticLabelMinFraction;
  const fs::path labels_dir = fs::path(folder) / "eval_only" / "class";
  for (ImageListEntry& entry : list.entries) {
    entry.label_image = (labels_dir / fs::path(entry.image).stem()).string() + ".png";
    std::error_code ec;
    if (!fs::is_regular_file(entry.label_image, ec)) {
      ThrowInFile(entry.label_image, "class image of " + entry.image +
                                         " does not exist (crop labels need the generator's "
                                         "eval_only/class)");
    }
  }
  return list;
}

ImageList KeepClasses(const ImageList& list, const std::vector<std::string>& keep,
                      const std::string& background) {
  ImageList out;
  out.background = background;
  out.label_min_fraction = list.label_min_fraction;
  std::vector<int> old_to_new(list.class_names.size(), -1);
  for (const std::string& name : keep) {
    const int old = list.ClassIndex(name);
    if (old < 0) {
      throw InputError(fmt::format("KeepClasses: unknown class '{}' (classes: {})", name,
                                   fmt::join(list.class_names, ", ")));
    }
    old_to_new[old] = out.num_classes();
    out.class_names.push_back(name);
    out.movable.push_back(list.movable[old]);
  }
  // Label ids map through the old classes (identity when the old list had no mapping).
  const size_t ids =
      list.label_to_class.empty() ? list.class_names.size() : list.label_to_class.size();
  out.label_to_class.assign(ids, -1);
  for (size_t id = 0; id < ids; ++id) {
    const int old = list.label_to_class.empty() ? static_cast<int>(id) : list.label_to_class[id];
    if (old >= 0) out.label_to_class[id] = old_to_new[old];
  }
  for (const ImageListEntry& entry : list.entries) {
    ImageListEntry e = entry;
    e.classes.clear();
    for (int c : entry.classes) {
      if (old_to_new[c] >= 0) e.classes.push_back(old_to_new[c]);
    }
    std::sort(e.classes.begin(), e.classes.end());
    out.entries.push_back(std::move(e));
  }
  return out;
}

}  // namespace moslam::weak
