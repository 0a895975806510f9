#include "breccia/io/json_view.hpp"

#include <filesystem>
#include <fstream>

#include "breccia/core/error.hpp"
#include "breccia/core/text_file.hpp"

namespace breccia {

using nlohmann::json;

json read_json_object(const std::string& path) {
  const json j = json::parse(read_text_file(path, "a JSON file"), nullptr, false);
  if (j.is_discarded()) throw InputError(path, "", "", "not valid JSON (damaged or truncated?)");
  if (!j.is_object()) throw InputError(path, "", "", "expected a JSON object");
  return j;
}

const json* JsonView::member(const std::string& key) const {
  if (!j_->is_object()) wrong("", *j_, "an object");
  const auto it = j_->find(key);
  return it == j_->end() || it->is_null() ? nullptr : &*it;
}

void JsonView::wrong(const std::string& key, const json& v, const char* want) const {
  std::string shown = v.dump();
  if (shown.size() > 60) shown = shown.substr(0, 57) + "...";
  throw InputError(file_, key.empty() ? path_ : key_path(key), shown,
                   std::string("expected ") + want + " (the file is damaged or from another tool)");
}

bool JsonView::has(const std::string& key) const {
  return member(key) != nullptr;
}

JsonView JsonView::at(const std::string& key) const {
  const json* m = member(key);
  if (!m) throw InputError(file_, key_path(key), "(missing)", "a required key is missing");
  return JsonView(*m, file_, key_path(key));
}

std::optional<JsonView> JsonView::find(const std::string& key) const {
  const json* m = member(key);
  if (!m) return std::nullopt;
  if (!m->is_object() && !m->is_array()) wrong(key, *m, "an object or a list");
  return JsonView(*m, file_, key_path(key));
}

double JsonView::number(const std::string& key) const {
  const auto v = maybe_number(key);
  if (!v) throw InputError(file_, key_path(key), "(missing)", "a required number is missing");
  return *v;
}

std::optional<double> JsonView::maybe_number(const std::string& key) const {
  const json* m = member(key);
  if (!m) return std::nullopt;
  if (!m->is_number()) wrong(key, *m, "a number");
  return m->get<double>();
}

std::string JsonView::text(const std::string& key, const std::string& fallback) const {
  const json* m = member(key);
  if (!m) return fallback;
  if (!m->is_string()) wrong(key, *m, "a string");
  return m->get<std::string>();
}

bool JsonView::flag(const std::string& key, bool fallback) const {
  const json* m = member(key);
  if (!m) return fallback;
  if (!m->is_boolean()) wrong(key, *m, "true or false");
  return m->get<bool>();
}

std::vector<JsonView> JsonView::elements(const std::string& key) const {
  std::vector<JsonView> out;
  const json* m = member(key);
  if (!m) return out;
  if (!m->is_array()) wrong(key, *m, "a list");
  for (std::size_t k = 0; k < m->size(); ++k)
    out.emplace_back((*m)[k], file_, key_path(key) + "[" + std::to_string(k) + "]");
  return out;
}

double JsonView::as_number() const {
  if (!j_->is_number()) wrong("", *j_, "a number");
  return j_->get<double>();
}

std::string JsonView::as_text() const {
  if (!j_->is_string()) wrong("", *j_, "a string");
  return j_->get<std::string>();
}

}  // namespace breccia
