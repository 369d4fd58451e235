// Vocabulary files: this project's compact binary format and DBoW2's text format (ORB-SLAM2's
// ORBvoc.txt). The binary layout is documented in docs/VOCABULARY.md; everything is
// little-endian, written byte by byte so that files are portable.
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "moslam/util/check.h"
#include "moslam/util/error.h"
#include "moslam/vocab/vocabulary.h"

namespace moslam::vocab {
namespace {

constexpr char kMagic[8] = {'M', 'O', 'S', 'L', 'V', 'O', 'C', 'B'};
constexpr uint32_t kVersion = 1;
constexpr size_t kHeaderBytes = 8 + 5 * 4;

void PutU32(std::string* out, uint32_t v) {
  for (int i = 0; i < 4; ++i) out->push_back(static_cast<char>((v >> (8 * i)) & 0xffu));
}

void PutF64(std::string* out, double v) {
  uint64_t bits;
  std::memcpy(&bits, &v, 8);
  for (int i = 0; i < 8; ++i) out->push_back(static_cast<char>((bits >> (8 * i)) & 0xffu));
}

// Bounds-checked reader over the file's bytes; a short read names the file and offset.
class ByteReader {
 public:
  ByteReader(const std::string& path, const std::string& bytes) : path_(path), bytes_(bytes) {}
  uint32_t U32() {
    const uint8_t* p = Take(4);
    return static_cast<uint32_t>(p[0]) | static_cast<uint32_t>(p[1]) << 8 |
           static_cast<uint32_t>(p[2]) << 16 | static_cast<uint32_t>(p[3]) << 24;
  }
  uint8_t U8() { return *Take(1); }
  double F64() {
    const uint8_t* p = Take(8);
    uint64_t bits = 0;
    for (int i = 7; i >= 0; --i) bits = bits << 8 | p[i];
    double v;
    std::memcpy(&v, &bits, 8);
    return v;
  }
  const uint8_t* Take(size_t n) {
    if (bytes_.size() - offset_ < n) {
      ThrowInFile(path_, fmt::format("truncated vocabulary: needs {} bytes at offset {}, file "
                                     "has {}",
                                     n, offset_, bytes_.size()));
    }
    const uint8_t* p = reinterpret_cast<const uint8_t*>(bytes_.data()) + offset_;
    offset_ += n;
    return p;
  }
  size_t remaining() const { return bytes_.size() - offset_; }

 private:
  const std::string& path_;
  const std::string& bytes_;
  size_t offset_ = 0;
};

std::string ReadWholeFile(const std::string& path) {
  std::error_code error;
  if (std::filesystem::is_directory(path, error)) {
    ThrowInFile(path, "is a directory, not a vocabulary file");
  }
  std::ifstream file(path, std::ios::binary | std::ios::ate);
  if (!file) ThrowInFile(path, "cannot open vocabulary file");
  const std::streamoff size = file.tellg();
  if (size < 0) ThrowInFile(path, "cannot tell the size of the vocabulary file");
  std::string bytes(static_cast<size_t>(size), '\0');
  file.seekg(0);
  // One read into a buffer of the file's size: a 1M-word binary file is ~50 MB.
  if (!file.read(bytes.data(), size)) ThrowInFile(path, "error reading vocabulary file");
  return bytes;
}

void CheckShape(const std::string& path, long k, long levels) {
  if (k < 2 || k > 64) ThrowInFile(path, fmt::format("branching factor k = {} not in [2, 64]", k));
  if (levels < 1 || levels > 10) {
    ThrowInFile(path, fmt::format("levels = {} not in [1, 10]", levels));
  }
}

bool IsBlank(char c) { return c == ' ' || c == '\t' || c == '\r'; }

// Parses one non-negative integer field at *p (skipping blanks); false if there is none. The
// field must end at a blank or the end of the line: "0.5" is not the integer 0 followed by ".5"
// (a node line one descriptor byte short would otherwise read its weight as a byte).
bool ParseUnsigned(const char** p, const char* end, unsigned long* value) {
  const char* s = *p;
  while (s < end && IsBlank(*s)) ++s;
  if (s == end || *s < '0' || *s > '9') return false;
  unsigned long v = 0;
  while (s < end && *s >= '0' && *s <= '9') {
    v = v * 10 + static_cast<unsigned long>(*s - '0');
    if (v > 0xffffffffUL) return false;
    ++s;
  }
  if (s < end && !IsBlank(*s)) return false;
  *p = s;
  *value = v;
  return true;
}

// TF-IDF weights are logarithms of N / n_i >= 1: finite and never negative. A NaN, infinite or
// negative weight (a corrupt or hand-edited file) would poison every score that uses the word.
bool IsValidWeight(double weight) { return std::isfinite(weight) && weight >= 0.0; }

}  // namespace

void Vocabulary::Save(const std::string& path) const {
  MOSLAM_CHECK(!nodes_.empty()) << "saving an empty vocabulary";
  std::string out;
  out.reserve(kHeaderBytes + nodes_.size() * 37 + words_.size() * 8);
  out.append(kMagic, sizeof(kMagic));
  PutU32(&out, kVersion);
  PutU32(&out, static_cast<uint32_t>(k_));
  PutU32(&out, static_cast<uint32_t>(levels_));
  PutU32(&out, static_cast<uint32_t>(nodes_.size()));
  PutU32(&out, static_cast<uint32_t>(words_.size()));
  for (size_t i = 1; i < nodes_.size(); ++i) {
    const Node& node = nodes_[i];
    PutU32(&out, node.parent);
    const bool leaf = node.children.empty();
    out.push_back(leaf ? 1 : 0);
    out.append(reinterpret_cast<const char*>(node.descriptor), 32);
    if (leaf) PutF64(&out, node.weight);
  }
  std::ofstream file(path, std::ios::binary | std::ios::trunc);
  if (!file) ThrowInFile(path, "cannot create vocabulary file");
  file.write(out.data(), static_cast<std::streamsize>(out.size()));
  file.close();
  if (!file) ThrowInFile(path, "error writing vocabulary file");
}

namespace {

// Links children to parents and checks that the leaf flags agree with the tree.
template <typename Node>
void LinkChildren(const std::string& path, const std::vector<bool>& leaf,
                  std::vector<Node>* nodes) {
  for (size_t i = 1; i < nodes->size(); ++i) {
    const uint32_t parent = (*nodes)[i].parent;
    if (parent >= i) {
      ThrowInFile(path, fmt::format("node {} has parent {}, which does not precede it", i, parent));
    }
    if (leaf[parent]) ThrowInFile(path, fmt::format("node {} has leaf {} as parent", i, parent));
    (*nodes)[parent].children.push_back(static_cast<uint32_t>(i));
  }
  for (size_t i = 0; i < nodes->size(); ++i) {
    if (!leaf[i] && (*nodes)[i].children.empty() && i != 0) {
      ThrowInFile(path, fmt::format("node {} is not a leaf but has no children", i));
    }
  }
}

}  // namespace

Vocabulary Vocabulary::Load(const std::string& path) {
  const std::string bytes = ReadWholeFile(path);
  Vocabulary voc;
  if (bytes.size() >= sizeof(kMagic) && std::memcmp(bytes.data(), kMagic, sizeof(kMagic)) == 0) {
    voc.LoadBinary(path, bytes);
  } else if (!bytes.empty() && bytes[0] >= '0' && bytes[0] <= '9') {
    voc.LoadDbow2Text(path, bytes);
  } else {
    ThrowInFile(path,
                "not a vocabulary: neither moslam's binary format (magic MOSLVOCB) nor "
                "DBoW2 text (first line 'k L scoring weighting')");
  }
  return voc;
}

void Vocabulary::LoadBinary(const std::string& path, const std::string& bytes) {
  ByteReader in(path, bytes);
  in.Take(sizeof(kMagic));
  const uint32_t version = in.U32();
  if (version != kVersion) {
    ThrowInFile(
        path, fmt::format("vocabulary format version {} (this build reads {})", version, kVersion));
  }
  const uint32_t k = in.U32();
  const uint32_t levels = in.U32();
  CheckShape(path, k, levels);
  k_ = static_cast<int>(k);
  levels_ = static_cast<int>(levels);
  const uint32_t num_nodes = in.U32();
  const uint32_t num_words = in.U32();
  // Each node takes at least 37 bytes: reject absurd counts before allocating.
  if (num_nodes < 2 || (num_nodes - 1) > in.remaining() / 37) {
    ThrowInFile(path, fmt::format("node count {} does not fit the file size", num_nodes));
  }
  nodes_.assign(num_nodes, Node{});
  std::vector<bool> leaf(num_nodes, false);
  for (uint32_t i = 1; i < num_nodes; ++i) {
    Node& node = nodes_[i];
    node.parent = in.U32();
    const uint8_t flag = in.U8();
    if (flag > 1) ThrowInFile(path, fmt::format("node {}: bad leaf flag {}", i, flag));
    leaf[i] = flag == 1;
    std::memcpy(node.descriptor, in.Take(32), 32);
    if (leaf[i]) {
      node.weight = in.F64();
      if (!IsValidWeight(node.weight)) {
        ThrowInFile(path,
                    fmt::format("node {}: weight {} is not a finite number >= 0", i, node.weight));
      }
    }
  }
  if (in.remaining() != 0) {
    ThrowInFile(path, fmt::format("{} unexpected bytes after the last node", in.remaining()));
  }
  LinkChildren(path, leaf, &nodes_);
  IndexWords(path);
  if (words_.size() != num_words) {
    ThrowInFile(path,
                fmt::format("header says {} words, the tree has {}", num_words, words_.size()));
  }
}

void Vocabulary::LoadDbow2Text(const std::string& path, const std::string& bytes) {
  const char* p = bytes.data();
  const char* const end = p + bytes.size();
  int line = 1;
  const char* eol = static_cast<const char*>(std::memchr(p, '\n', bytes.size()));
  if (eol == nullptr) eol = end;
  {
    unsigned long header[4];
    for (unsigned long& v : header) {
      if (!ParseUnsigned(&p, eol, &v)) {
        ThrowAtLine(path, line, "DBoW2 header must be 'k L scoring_type weighting_type'");
      }
    }
    CheckShape(path, static_cast<long>(header[0]), static_cast<long>(header[1]));
    // Score() is DBoW2's L1 (0) of TF-IDF (0) vectors; other types would score differently.
    if (header[2] != 0 || header[3] != 0) {
      ThrowAtLine(path, line,
                  fmt::format("scoring {} / weighting {}: only L1 (0) and TF-IDF (0) "
                              "are supported",
                              header[2], header[3]));
    }
    k_ = static_cast<int>(header[0]);
    levels_ = static_cast<int>(header[1]);
  }
  nodes_.assign(1, Node{});
  std::vector<bool> leaf(1, false);
  for (p = eol; p < end; p = eol) {
    ++p;  // past '\n'
    ++line;
    eol = static_cast<const char*>(std::memchr(p, '\n', static_cast<size_t>(end - p)));
    if (eol == nullptr) eol = end;
    const char* q = p;
    while (q < eol && (*q == ' ' || *q == '\t' || *q == '\r')) ++q;
    if (q == eol) continue;  // blank line (DBoW2 files end with one)
    Node node;
    unsigned long parent, is_leaf, byte;
    if (!ParseUnsigned(&q, eol, &parent) || !ParseUnsigned(&q, eol, &is_leaf) || is_leaf > 1) {
      ThrowAtLine(path, line, "node line must be 'parent_id is_leaf d0 ... d31 weight'");
    }
    for (uint8_t& d : node.descriptor) {
      if (!ParseUnsigned(&q, eol, &byte) || byte > 255) {
        ThrowAtLine(path, line, "expected 32 descriptor bytes in [0, 255]");
      }
      d = static_cast<uint8_t>(byte);
    }
    const std::string rest(q, eol);
    char* weight_end = nullptr;
    errno = 0;
    node.weight = std::strtod(rest.c_str(), &weight_end);
    if (weight_end == rest.c_str() || errno != 0) ThrowAtLine(path, line, "expected a weight");
    if (!IsValidWeight(node.weight)) {
      ThrowAtLine(path, line, fmt::format("weight {} is not a finite number >= 0", node.weight));
    }
    for (const char* t = weight_end; *t != '\0'; ++t) {
      if (*t != ' ' && *t != '\t' && *t != '\r') ThrowAtLine(path, line, "extra text after weight");
    }
    node.parent = static_cast<uint32_t>(parent);
    if (node.parent >= nodes_.size()) {
      ThrowAtLine(path, line, fmt::format("parent {} is not an earlier node", parent));
    }
    nodes_.push_back(node);
    leaf.push_back(is_leaf == 1);
  }
  LinkChildren(path, leaf, &nodes_);
  IndexWords(path);
}

}  // namespace moslam::vocab
