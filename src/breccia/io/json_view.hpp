#pragma once
// Checked reading of the JSON files Breccia reads back (summaries, manifests, sweep files, sample
// sidecars): every access names the file and the key path when the key is missing or has the
// wrong type, so no library message (or undefined behaviour of a missing key) reaches the user.
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace breccia {

// Reads a JSON object from `path`; throws InputError naming the file when it cannot be read, is
// not valid JSON, or is not an object.
nlohmann::json read_json_object(const std::string& path);

class JsonView {
 public:
  JsonView(const nlohmann::json& j, std::string file, std::string path = "")
      : j_(&j), file_(std::move(file)), path_(std::move(path)) {}

  bool has(const std::string& key) const;  // present and not null
  // A member that must be present (any type but null).
  JsonView at(const std::string& key) const;
  // A member that must be an object or array when present; nullopt when absent or null.
  std::optional<JsonView> find(const std::string& key) const;
  // Numbers: required, or nullopt when absent or null (NaN is written as null).
  double number(const std::string& key) const;
  std::optional<double> maybe_number(const std::string& key) const;
  std::string text(const std::string& key, const std::string& fallback) const;
  bool flag(const std::string& key, bool fallback) const;
  // Elements of an array member (empty when absent).
  std::vector<JsonView> elements(const std::string& key) const;
  // This node as a number or string; throws unless it is one.
  double as_number() const;
  std::string as_text() const;

  const nlohmann::json& raw() const noexcept { return *j_; }
  std::string key_path(const std::string& key) const {
    return path_.empty() ? key : path_ + "." + key;
  }

 private:
  const nlohmann::json* member(const std::string& key) const;  // null when absent
  [[noreturn]] void wrong(const std::string& key, const nlohmann::json& v, const char* want) const;

  const nlohmann::json* j_;
  std::string file_, path_;
};

}  // namespace breccia
