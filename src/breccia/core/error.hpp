#pragma once
// Errors that reach users. An InputError names where the bad value came from (file and line, or
// key), the value and what is allowed, so the message alone is enough to fix the input.
#include <stdexcept>
#include <string>

namespace breccia {

class InputError : public std::runtime_error {
 public:
  InputError(std::string where, std::string key, std::string value, std::string allowed)
      : std::runtime_error(compose(where, key, value, allowed)),
        where_(std::move(where)),
        key_(std::move(key)),
        value_(std::move(value)),
        allowed_(std::move(allowed)) {}

  const std::string& where() const noexcept { return where_; }
  const std::string& key() const noexcept { return key_; }
  const std::string& value() const noexcept { return value_; }
  const std::string& allowed() const noexcept { return allowed_; }

 private:
  static std::string compose(const std::string& where, const std::string& key,
                             const std::string& value, const std::string& allowed) {
    std::string m = where;
    if (!key.empty()) m += ": '" + key + "'";
    if (!value.empty()) m += " = " + value;
    if (!allowed.empty()) m += ": " + allowed;
    return m;
  }
  std::string where_, key_, value_, allowed_;
};

// A broken internal invariant: a bug, never the user's input.
class InternalError : public std::logic_error {
 public:
  using std::logic_error::logic_error;
};

}  // namespace breccia
