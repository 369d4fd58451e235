// Place recognition with a bag-of-words vocabulary on a held-out sequence with ground-truth
// poses, against a whole-image baseline and chance. Developer measurement for issue 9
// (docs/VOCABULARY.md).
//
//   vocab_eval --vocab data/vocab/moslam_orb.mvoc --data DIR [--db-every 5] [--query-offset 2]
//              [--exclude-s 3] [--max-dist 0.3] [--max-angle-deg 15] [--threads 2]
//
// Protocol: frames i with i % db_every == 0 form the database, frames with
// i % db_every == query_offset are the queries (so no query is a database image). For a query,
// database frames closer in time than --exclude-s are not candidates (a loop-closure protocol:
// they would match trivially); 0 keeps them all (a relocalization protocol). A retrieved frame
// is correct when its camera lies within --max-dist metres and --max-angle-deg degrees of the
// query's (ground truth). Reported per method:
//   positives   queries with at least one correct candidate;
//   R@1, R@5    fraction of positives whose best (any of the 5 best) candidate is correct;
//   P@R50       queries ranked by the score of their best candidate: the precision when half of
//               the positives have been retrieved correctly (queries without a correct candidate
//               count as false when accepted);
//   R@P100      the fraction of positives retrieved before the first false acceptance.
// Methods: BoW (each --vocab: TF-IDF L1 score through vocab::Database), "tiny image" (grey
// image resized to 48 px wide, zero-mean unit-norm, dot product: the whole-image baseline of
// SeqSLAM-like systems), and chance (the expected R@1 of a uniformly random candidate).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "moslam/eval/trajectory_io.h"
#include "moslam/io/dataset.h"
#include "moslam/util/error.h"
#include "moslam/util/log.h"
#include "moslam/vocab/database.h"
#include "moslam/vocab/image_descriptors.h"
#include "moslam/vocab/vocabulary.h"

namespace {

using moslam::geometry::SE3;

struct Frame {
  std::string image;
  double time = 0.0;
  SE3 pose;  // T_world_cam (ground truth)
};

struct Args {
  std::vector<std::string> vocabs;
  std::string data;
  int db_every = 5;
  int query_offset = 2;
  double exclude_s = 3.0;
  double max_dist = 0.3;
  double max_angle_deg = 15.0;
  int threads = 1;
  int max_features = 1000;
  int max_frames = 0;
};

// Frames of the data set that have a ground-truth pose: by timestamp (nearest within 20 ms) when
// the ground truth has stamps, else by index (KITTI poses.txt).
std::vector<Frame> LoadFrames(const Args& args) {
  const moslam::io::Sequence seq = moslam::io::ReadDataset(args.data);
  if (!seq.ground_truth_path) moslam::ThrowInFile(args.data, "data set has no ground truth");
  const moslam::eval::Trajectory gt = moslam::eval::ReadTrajectory(*seq.ground_truth_path);
  std::vector<Frame> frames;
  for (const moslam::io::FrameEntry& f : seq.frames) {
    if (args.max_frames > 0 && f.index >= args.max_frames) break;
    size_t k = static_cast<size_t>(f.index);
    if (gt.has_timestamps()) {
      const auto it = std::lower_bound(gt.timestamps.begin(), gt.timestamps.end(), f.timestamp);
      k = static_cast<size_t>(it - gt.timestamps.begin());
      if (k > 0 &&
          (k == gt.size() || f.timestamp - gt.timestamps[k - 1] < gt.timestamps[k] - f.timestamp)) {
        --k;
      }
      if (k >= gt.size() || std::abs(gt.timestamps[k] - f.timestamp) > 0.02) continue;
    } else if (k >= gt.size()) {
      moslam::ThrowInFile(*seq.ground_truth_path, "fewer poses than frames");
    }
    frames.push_back({f.image_left, f.timestamp, gt.poses[k]});
  }
  return frames;
}

bool SamePlace(const SE3& a, const SE3& b, const Args& args) {
  const double dist = (a.translation() - b.translation()).norm();
  const double angle = a.rotation().angularDistance(b.rotation()) * 180.0 / M_PI;
  return dist <= args.max_dist && angle <= args.max_angle_deg;
}

struct Split {
  std::vector<size_t> db, queries;                       // frame indices
  std::vector<std::vector<bool>> candidate, true_match;  // [query][db]
};

Split MakeSplit(const std::vector<Frame>& frames, const Args& args) {
  Split s;
  for (size_t i = 0; i < frames.size(); ++i) {
    const int r = static_cast<int>(i % static_cast<size_t>(args.db_every));
    if (r == 0) s.db.push_back(i);
    if (r == args.query_offset) s.queries.push_back(i);
  }
  for (size_t q : s.queries) {
    std::vector<bool> cand(s.db.size()), match(s.db.size());
    for (size_t j = 0; j < s.db.size(); ++j) {
      cand[j] = std::abs(frames[q].time - frames[s.db[j]].time) >= args.exclude_s;
      match[j] = cand[j] && SamePlace(frames[q].pose, frames[s.db[j]].pose, args);
    }
    s.candidate.push_back(cand);
    s.true_match.push_back(match);
  }
  return s;
}

// Per query: candidate database positions, best first, and the best score.
struct Ranking {
  std::vector<std::vector<size_t>> ranked;
  std::vector<double> best_score;
};

void PrintMetrics(const std::string& name, const Split& s, const Ranking& r) {
  int positives = 0, r1 = 0, r5 = 0;
  std::vector<std::pair<double, int>> accepted;  // (score, 1 correct / 0 false / -1 no match)
  for (size_t q = 0; q < s.queries.size(); ++q) {
    const bool positive =
        std::find(s.true_match[q].begin(), s.true_match[q].end(), true) != s.true_match[q].end();
    positives += positive;
    if (r.ranked[q].empty()) continue;
    const bool top1 = s.true_match[q][r.ranked[q][0]];
    bool top5 = false;
    for (size_t i = 0; i < std::min<size_t>(5, r.ranked[q].size()); ++i) {
      top5 = top5 || s.true_match[q][r.ranked[q][i]];
    }
    r1 += positive && top1;
    r5 += positive && top5;
    accepted.push_back({r.best_score[q], top1 ? 1 : 0});
  }
  std::sort(accepted.begin(), accepted.end(),
            [](const auto& a, const auto& b) { return a.first > b.first; });
  double precision_at_half = 0.0, recall_at_full = 0.0;
  int tp = 0, fp = 0;
  bool clean = true;
  for (const auto& [score, correct] : accepted) {
    (correct ? tp : fp) += 1;
    if (fp > 0) clean = false;
    if (clean) recall_at_full = static_cast<double>(tp) / std::max(positives, 1);
    if (precision_at_half == 0.0 && 2 * tp >= positives && positives > 0) {
      precision_at_half = static_cast<double>(tp) / (tp + fp);
    }
  }
  const double n = std::max(positives, 1);
  std::printf("%-34s %9d %6.3f %6.3f %6.3f %7.3f\n", name.c_str(), positives, r1 / n, r5 / n,
              precision_at_half, recall_at_full);
}

Ranking RankBow(const std::string& vocab_path, const std::vector<cv::Mat>& descriptors,
                const Split& s) {
  const moslam::vocab::Vocabulary voc = moslam::vocab::Vocabulary::Load(vocab_path);
  moslam::vocab::Database db;
  for (size_t j = 0; j < s.db.size(); ++j) {
    moslam::vocab::BowVector bow;
    voc.Transform(descriptors[s.db[j]], &bow, nullptr, 0);
    db.Add(j, bow);
  }
  Ranking r;
  for (size_t q = 0; q < s.queries.size(); ++q) {
    moslam::vocab::BowVector bow;
    voc.Transform(descriptors[s.queries[q]], &bow, nullptr, 0);
    std::vector<size_t> ranked;
    double best = 0.0;
    for (const moslam::vocab::QueryResult& result : db.Query(bow, -1, 0.0)) {
      if (!s.candidate[q][result.id]) continue;
      if (ranked.empty()) best = result.score;
      ranked.push_back(result.id);
    }
    r.ranked.push_back(ranked);
    r.best_score.push_back(best);
  }
  return r;
}

cv::Mat TinyImage(const std::string& path) {
  const cv::Mat grey = cv::imread(path, cv::IMREAD_GRAYSCALE);
  if (grey.empty()) moslam::ThrowInFile(path, "cannot be read as an image");
  const int width = 48;
  const int height = std::max(8, static_cast<int>(std::lround(48.0 * grey.rows / grey.cols)));
  cv::Mat small;
  cv::resize(grey, small, cv::Size(width, height), 0, 0, cv::INTER_AREA);
  small.convertTo(small, CV_64F);
  small -= cv::mean(small)[0];
  const double norm = cv::norm(small);
  if (norm > 0) small /= norm;
  return small;
}

Ranking RankTiny(const std::vector<Frame>& frames, const Split& s) {
  std::vector<cv::Mat> db(s.db.size());
  for (size_t j = 0; j < s.db.size(); ++j) db[j] = TinyImage(frames[s.db[j]].image);
  Ranking r;
  for (size_t q = 0; q < s.queries.size(); ++q) {
    const cv::Mat query = TinyImage(frames[s.queries[q]].image);
    std::vector<std::pair<double, size_t>> scored;
    for (size_t j = 0; j < db.size(); ++j) {
      if (s.candidate[q][j]) scored.push_back({-query.dot(db[j]), j});
    }
    std::sort(scored.begin(), scored.end());
    std::vector<size_t> ranked;
    for (const auto& [score, j] : scored) ranked.push_back(j);
    r.ranked.push_back(ranked);
    r.best_score.push_back(scored.empty() ? 0.0 : -scored[0].first);
  }
  return r;
}

void PrintChance(const Split& s) {
  double expected = 0.0;
  int positives = 0;
  for (size_t q = 0; q < s.queries.size(); ++q) {
    const auto count = [](const std::vector<bool>& v) {
      return static_cast<double>(std::count(v.begin(), v.end(), true));
    };
    const double matches = count(s.true_match[q]);
    if (matches == 0) continue;
    ++positives;
    expected += matches / count(s.candidate[q]);
  }
  std::printf("%-34s %9d %6.3f %6s %6s %7s\n", "chance (random candidate)", positives,
              expected / std::max(positives, 1), "-", "-", "-");
}

void Run(const Args& args) {
  const std::vector<Frame> frames = LoadFrames(args);
  if (args.db_every < 1 || args.query_offset <= 0 || args.query_offset >= args.db_every) {
    moslam::ThrowInput("need --db-every >= 2 and 0 < --query-offset < --db-every");
  }
  const Split s = MakeSplit(frames, args);
  std::printf(
      "%s: %zu frames with ground truth; database %zu (every %d), queries %zu "
      "(offset %d); exclusion %.1f s; correct within %.2f m and %.1f deg\n",
      args.data.c_str(), frames.size(), s.db.size(), args.db_every, s.queries.size(),
      args.query_offset, args.exclude_s, args.max_dist, args.max_angle_deg);
  std::vector<std::string> paths;
  for (const Frame& f : frames) paths.push_back(f.image);
  moslam::feature::OrbExtractorOptions orb;
  orb.num_features = args.max_features;
  // Only database and query frames are needed; the others stay empty.
  std::vector<size_t> used_index;
  for (size_t i : s.db) used_index.push_back(i);
  for (size_t i : s.queries) used_index.push_back(i);
  std::vector<std::string> used_paths;
  for (size_t i : used_index) used_paths.push_back(paths[i]);
  const std::vector<cv::Mat> extracted =
      moslam::vocab::ExtractDescriptors(used_paths, orb, args.threads);
  std::vector<cv::Mat> descriptors(paths.size());
  for (size_t k = 0; k < used_index.size(); ++k) descriptors[used_index[k]] = extracted[k];

  std::printf("%-34s %9s %6s %6s %6s %7s\n", "method", "positives", "R@1", "R@5", "P@R50",
              "R@P100");
  for (const std::string& vocab : args.vocabs) {
    PrintMetrics("BoW " + vocab, s, RankBow(vocab, descriptors, s));
  }
  PrintMetrics("tiny image (48 px, NCC)", s, RankTiny(frames, s));
  PrintChance(s);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app("vocab_eval: place recognition of BoW vocabularies on a sequence with poses");
  Args args;
  std::string log_level = "info";
  app.add_option("--vocab", args.vocabs, "Vocabulary files (binary or DBoW2 text)")
      ->required()
      ->expected(1, -1);
  app.add_option("--data", args.data, "Data-set folder with ground truth (TUM, KITTI, ...)")
      ->required();
  app.add_option("--db-every", args.db_every, "Database = frames i % N == 0")
      ->capture_default_str();
  app.add_option("--query-offset", args.query_offset, "Queries = frames i % N == offset")
      ->capture_default_str();
  app.add_option("--exclude-s", args.exclude_s,
                 "Database frames closer in time than this are not candidates (seconds)")
      ->capture_default_str();
  app.add_option("--max-dist", args.max_dist, "Correct within this distance (metres)")
      ->capture_default_str();
  app.add_option("--max-angle-deg", args.max_angle_deg, "... and this rotation (degrees)")
      ->capture_default_str();
  app.add_option("--threads", args.threads, "ORB extraction threads")->capture_default_str();
  app.add_option("--max-features", args.max_features, "ORB features per image")
      ->capture_default_str();
  app.add_option("--max-frames", args.max_frames, "First N frames only (0: all)")
      ->capture_default_str();
  app.add_option("--log-level", log_level, "Log level")->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  moslam::SetupLogging(log_level);
  try {
    Run(args);
  } catch (const moslam::InputError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  }
  return 0;
}
