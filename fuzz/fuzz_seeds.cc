// The seed corpus of the fuzz harnesses (fuzz_targets.h): small valid inputs of every parser,
// generated rather than committed, so that the repository holds no binary seeds.
#include <filesystem>
#include <fstream>
#include <random>

#include "fuzz_targets.h"
#include "moslam/mapio/test_map.h"
#include "moslam/util/check.h"
#include "moslam/vocab/vocabulary.h"

namespace moslam::fuzz {
namespace fs = std::filesystem;
namespace {

void Write(const fs::path& path, const std::string& bytes) {
  fs::create_directories(path.parent_path());
  std::ofstream file(path, std::ios::binary | std::ios::trunc);
  file.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  MOSLAM_CHECK(file.good()) << "cannot write the seed " << path.string();
}

int CopyYamlFiles(const fs::path& from, const fs::path& to) {
  int n = 0;
  if (!fs::is_directory(from)) return 0;
  for (const auto& entry : fs::directory_iterator(from)) {
    if (entry.path().extension() != ".yaml") continue;
    fs::create_directories(to);
    fs::copy_file(entry.path(), to / entry.path().filename(), fs::copy_options::overwrite_existing);
    ++n;
  }
  return n;
}

// The model cards of configs/models with their files renamed to the scratch folder's stand-ins
// (model.<extension of the file named>, model.cfg), so that every seed gets past the file lookup
// into the checks behind it; the files themselves are not read by the card parser.
int CopyModelCards(const fs::path& from, const fs::path& to) {
  int n = 0;
  if (!fs::is_directory(from)) return 0;
  for (const auto& entry : fs::directory_iterator(from)) {
    if (entry.path().extension() != ".yaml") continue;
    std::ifstream in(entry.path());
    std::string card, line;
    while (std::getline(in, line)) {
      if (line.rfind("model:", 0) == 0) {
        line = "model: model" + fs::path(line.substr(6)).extension().string();
      } else if (line.rfind("config:", 0) == 0) {
        line = "config: model.cfg";
      }
      card += line + "\n";
    }
    Write(to / entry.path().filename(), card);
    ++n;
  }
  return n;
}

// A vocabulary of 3x3 words trained on random descriptors, in the binary format, and a DBoW2
// text vocabulary written out by hand (k = 2, L = 1: two words).
int WriteVocabularies(const fs::path& dir) {
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> byte(0, 255);
  std::vector<cv::Mat> images;
  for (int i = 0; i < 4; ++i) {
    cv::Mat d(40, 32, CV_8U);
    for (int r = 0; r < d.rows; ++r) {
      for (int c = 0; c < 32; ++c) d.at<uint8_t>(r, c) = static_cast<uint8_t>(byte(rng));
    }
    images.push_back(d);
  }
  vocab::VocabularyTrainOptions options;
  options.k = 3;
  options.levels = 2;
  fs::create_directories(dir);
  vocab::Vocabulary::Train(images, options).Save((dir / "trained.mvoc").string());
  std::string text = "2 1 0 0\n";
  for (int word = 0; word < 2; ++word) {
    text += "0 1";
    for (int b = 0; b < 32; ++b) text += " " + std::to_string(word == 0 ? b : 255 - b);
    text += " 0.693147\n";
  }
  Write(dir / "dbow2.txt", text);
  return 2;
}

// A small map's body (the header is the harness's), with the harness's identity.
int WriteMapBody(const fs::path& dir) {
  map::Map map;
  mapio::testing::BuildTestMap(4, 24, 3, &map);
  std::string bytes;
  {
    std::lock_guard<std::mutex> lock(map.mutex());
    bytes = mapio::SerializeMap(map, FuzzMapIdentity());
  }
  Write(dir / "small.map", bytes.substr(mapio::kMapPrefixBytes));  // the harness seals it
  return 1;
}

}  // namespace

int WriteSeeds(const std::string& source_dir, const std::string& out_dir) {
  const fs::path src(source_dir), out(out_dir);
  int n = 0;
  n += CopyYamlFiles(src / "configs", out / "settings");
  n += CopyModelCards(src / "configs" / "models", out / "model_card");
  Write(out / "model_card" / "minimal.yaml",
        "%YAML:1.0\ntype: segmentation\nmodel: model.onnx\ninput_width: 64\ninput_height: 64\n"
        "classes: [background, person]\nmovable: [person]\nbackground: background\n");
  Write(out / "tum_list" / "rgb.txt",
        "# color images\n# file: 'x.bag'\n# timestamp filename\n1305031102.175304 rgb/1.png\n"
        "1305031102.211214 rgb/1.png\n");
  Write(out / "kitti_calib" / "calib.txt",
        "P0: 718.856 0 607.1928 0 0 718.856 185.2157 0 0 0 1 0\n"
        "P1: 718.856 0 607.1928 -386.1448 0 718.856 185.2157 0 0 0 1 0\n"
        "P2: 718.856 0 607.1928 45.38225 0 718.856 185.2157 -0.1130887 0 0 1 0.003779761\n"
        "P3: 718.856 0 607.1928 -337.2877 0 718.856 185.2157 2.369057 0 0 1 0.004915215\n"
        "Tr: 4.276802e-04 -9.999672e-01 -8.084491e-03 -1.198459e-02 -7.210626e-03 "
        "8.081198e-03 -9.999413e-01 -5.403984e-02 9.999738e-01 4.859485e-04 -7.206933e-03 "
        "-2.921968e-01\n");
  Write(out / "kitti_times" / "times.txt", "0.000000e+00\n1.036400e-01\n2.072800e-01\n");
  Write(out / "trajectory" / "tum.txt",
        "# timestamp tx ty tz qx qy qz qw\n1305031102.1753 1.3405 0.6266 1.6575 0.6574 0.6126 "
        "-0.2949 -0.3248\n1305031102.2113 1.3303 0.6256 1.6464 0.6579 0.6161 -0.2932 -0.3189\n");
  Write(out / "trajectory" / "kitti.txt",
        "1 0 0 0 0 1 0 0 0 0 1 0\n0.99995 -0.0099998 0 0.1 0.0099998 0.99995 0 0.02 0 0 1 0.8\n");
  Write(out / "trajectory" / "euroc.csv",
        "#timestamp,p_RS_R_x [m],p_RS_R_y [m],p_RS_R_z [m],q_RS_w [],q_RS_x [],q_RS_y [],"
        "q_RS_z []\n1403636579758555392,4.688,-1.786,0.783,0.534,-0.153,-0.827,-0.082\n"
        "1403636579763555584,4.688,-1.786,0.787,0.534,-0.152,-0.827,-0.082\n");
  n += 7;
  n += WriteVocabularies(out / "vocabulary");
  n += WriteMapBody(out / "map");
  return n;
}

}  // namespace moslam::fuzz
