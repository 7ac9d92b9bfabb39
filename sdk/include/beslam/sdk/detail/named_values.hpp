// Storage for the named values a backend returns (stage times, counters) in their C form.
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace beslam::sdk {

namespace detail {

// Named values (stage times, counters) as the C structs T {const char* name; double value} the host reads;
// the names are owned here and live until the next set().
template <class T>
class NamedValues {
 public:
  void set(const std::vector<std::pair<std::string, double>>& values) {
    names_.clear();
    items_.clear();
    for (const auto& [name, value] : values) names_.push_back(name);
    for (size_t i = 0; i < values.size(); ++i) items_.push_back({names_[i].c_str(), values[i].second});
  }
  const T* data() const { return items_.empty() ? nullptr : items_.data(); }
  uint32_t size() const { return static_cast<uint32_t>(items_.size()); }

 private:
  std::vector<std::string> names_;
  std::vector<T> items_;
};

}  // namespace detail

}  // namespace beslam::sdk
