// Training data of the weakly supervised pipeline: images with image-level class labels only.
//
// Image-list format (UTF-8 text, one image per line; what `moslam synth --train` writes as
// labels.txt, so its output is a ready training set):
//   # comment
//   <image path> <class name> <class name> ...
// Paths are relative to the list file's folder unless absolute; names must be among the dataset's
// classes (a classes file: `<id> <name> <movable 0|1>` per line, or a list of names given in code).
// A line without class names is an image where none of the listed classes occurs.
//
// CamVid (Brostow et al. 2009, SegNet split in ../shared/data/camvid): image-level labels are
// derived from the label PNGs — a class is present when it covers at least 0.1 % of the image (or
// of a crop: crops are labelled by what they contain). The label PNG is read only for that
// count; no pixel label ever reaches a loss (the `label_image` path is never handed to training
// code other than through CropLabels()).
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace moslam::weak {

struct ImageListEntry {
  std::string image;         // absolute or list-relative path, resolved when read
  std::vector<int> classes;  // indices into ImageList::class_names, sorted, unique
  // CamVid only: the id PNG from which crop labels are counted (never used as pixel supervision).
  std::string label_image;
};

struct ImageList {
  std::vector<std::string> class_names;
  std::vector<bool> movable;  // per class
  std::string background;     // name of the "none of the others" class, or empty
  std::vector<ImageListEntry> entries;
  // The rule by which entries with a label_image were labelled (ReadCamVid's min_fraction):
  // crops are relabelled by the same rule (augment.h).
  double label_min_fraction = 0.001;
  // Label id (in label images) -> class index, -1 for ids that belong to no class (e.g. merged
  // into the background by KeepClasses); empty means the identity (id = class index).
  std::vector<int> label_to_class;

  int num_classes() const { return static_cast<int>(class_names.size()); }
  int ClassIndex(const std::string& name) const;  // -1 when absent
};

// Reads a classes file (`<id> <name> <movable>`; ids must be 0..n-1 in order). A class named
// "background" becomes ImageList::background and is not a label of the list.
// InputError naming the file and line.
ImageList ReadClassesFile(const std::string& path);

// Writes `list`'s classes in ReadClassesFile's format (the background class first, as id 0,
// when there is one: the synthetic generator's layout).
void WriteClassesFile(const std::string& path, const ImageList& list);

// Reads an image list against `classes` (its class_names/movable/background are kept, entries
// replaced). InputError naming the file, line and the unknown class or missing image. The image
// path is the first whitespace-separated field (paths with spaces are not supported); a field
// starting with '#' ends the line (a trailing comment); the background class's name is accepted
// and ignored (it is implicitly present everywhere).
ImageList ReadImageList(const std::string& path, ImageList classes);
// Image paths are written relative to the list's folder when they lie below it, else absolute.
// label_image is not part of the format (a written CamVid list keeps its whole-image labels only).
void WriteImageList(const std::string& path, const ImageList& list);

// Every `every`-th entry (1-based: entries every-1, 2*every-1, ...) when `holdout` is true, the
// others when false: a deterministic split into training and held-out parts. every >= 2
// (InputError otherwise).
ImageList SplitHoldout(const ImageList& list, int every, bool holdout);

// The list restricted to the classes `keep` (by name, in that order); every other class is
// merged into a background class named `background` (e.g. CamVid's stuff classes become
// "background" for a car/pedestrian/bicyclist model). Image labels and label_to_class follow.
// InputError naming an unknown class.
ImageList KeepClasses(const ImageList& list, const std::vector<std::string>& keep,
                      const std::string& background = "background");

// CamVid: images in <root>/<split>/, labels in <root>/<split>annot/ (ids 0..11, 11 = unlabelled,
// never a class). Classes are CamVid's 11 named classes in id order; Car, Pedestrian and
// Bicyclist are movable; no background class. `min_fraction` of the image makes a class present.
ImageList ReadCamVid(const std::string& root, const std::string& split,
                     double min_fraction = 0.001);

// Classes present in `roi` of a CamVid id image (pixels with id >= num_classes are ignored), by
// the same `min_fraction` rule relative to the roi's area.
std::vector<int> CropLabels(const cv::Mat& label_ids, const cv::Rect& roi, int num_classes,
                            double min_fraction = 0.001);

// Cell (row r, column c) of a rows x cols grid of equal cells over `area`: the integer split
// x0 = area.x + c * area.width / cols (and likewise for y) that the label grid of augment.h and the
// per-cell cue operations of cues.h share, so that a cell's labels and its pixels agree.
cv::Rect GridCell(const cv::Rect& area, int r, int c, int rows, int cols);

// The synthetic generator's training mode folder (rgb/, labels.txt, classes.txt). With
// `crop_labels`, each entry's label_image is the generator's eval_only/class/<stem>.png (ids of
// classes.txt, 255 = no label), so that crops and label-grid cells are labelled by what they
// contain, exactly as CamVid's are: the image is read only to count classes (CropLabels), by the
// generator's own image-level rule (kSyntheticLabelMinFraction); no pixel label reaches a loss.
// InputError naming a missing class image.
ImageList ReadSyntheticTraining(const std::string& folder, bool crop_labels = false);

// The generator's image-level rule (synth/generator.cc LabelMinPixels: 200 pixels of a 640x480
// frame, scaled with the frame's area) as a fraction of the image, used for crops and cells.
inline constexpr double kSyntheticLabelMinFraction = 200.0 / (640.0 * 480.0);

}  // namespace moslam::weak
