// Options files: YAML (including OpenCV's "%YAML:1.0" dialect used by ORB-SLAM2 settings) read
// with key tracking, so that an unknown or misspelt key is an error naming the key and the file.
//
// Keys are addressed by their full dotted path: a top-level "Camera.fx" (ORB-SLAM2's flat style)
// and a nested "tracking: {iterations: 4}" ("tracking.iterations") are found the same way.
// Usage, in an options loader:
//
//   YamlFile file(path);
//   file.Read("ORBextractor.nFeatures", &options.num_features);  // optional, keeps the default
//   options.fx = file.Required<double>("Camera.fx");
//   file.IgnorePrefix("Viewer.");
//   file.RejectUnread();  // throws on the first key nobody asked for
#pragma once

#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

namespace moslam {

class YamlFile {
 public:
  // Throws InputError when the file is missing or is not valid YAML.
  explicit YamlFile(const std::string& path);
  ~YamlFile();
  YamlFile(YamlFile&&) noexcept;
  YamlFile& operator=(YamlFile&&) noexcept;

  const std::string& path() const { return path_; }
  bool Has(const std::string& key) const;
  // All leaf keys in file order of discovery (sorted), for diagnostics.
  std::vector<std::string> Keys() const;

  // Sets *value when the key is present (and marks it read); throws InputError naming the key
  // and the file when the value has the wrong type. Supported: double, float, int, bool,
  // std::string, std::vector<double>, std::vector<std::string>.
  template <typename T>
  bool Read(const std::string& key, T* value);
  // Like Read, but a missing key is an InputError.
  template <typename T>
  T Required(const std::string& key);

  // Marks every key starting with `prefix` as known (accepted and ignored).
  void IgnorePrefix(const std::string& prefix);
  // Throws InputError naming the first key that was neither read nor ignored.
  void RejectUnread() const;

 private:
  struct Impl;
  std::string path_;
  std::unique_ptr<Impl> impl_;
  std::set<std::string> read_;
  std::vector<std::string> ignored_prefixes_;
};

// The supported value types (defined in yaml.cc).
template <>
bool YamlFile::Read<double>(const std::string& key, double* value);
template <>
bool YamlFile::Read<float>(const std::string& key, float* value);
template <>
bool YamlFile::Read<int>(const std::string& key, int* value);
template <>
bool YamlFile::Read<bool>(const std::string& key, bool* value);
template <>
bool YamlFile::Read<std::string>(const std::string& key, std::string* value);
template <>
bool YamlFile::Read<std::vector<double>>(const std::string& key, std::vector<double>* value);
template <>
bool YamlFile::Read<std::vector<std::string>>(const std::string& key,
                                              std::vector<std::string>* value);

}  // namespace moslam
