#pragma once
// LabelSet: the set S(.) of subdomain labels incident to a simplex (thesis
// eq. 2.1), small and sorted. A vertex of a multi-material mesh rarely sees
// more than a handful of labels; a set that would exceed the capacity is
// flagged as overflowing and the remesher then treats its simplex as fixed.

#include <array>
#include <cstdint>
#include <string>

namespace vox::remesh {

class LabelSet {
public:
  static constexpr int kCapacity = 14;

  LabelSet() = default;

  void insert(std::int32_t label) {
    int i = 0;
    while (i < size_ && items_[i] < label) ++i;
    if (i < size_ && items_[i] == label) return;
    if (size_ == kCapacity) {
      overflow_ = true;
      return;
    }
    for (int k = size_; k > i; --k) items_[k] = items_[k - 1];
    items_[i] = label;
    ++size_;
  }
  void insertAll(const LabelSet& other) {
    for (int i = 0; i < other.size_; ++i) insert(other.items_[i]);
    overflow_ = overflow_ || other.overflow_;
  }

  bool contains(std::int32_t label) const {
    for (int i = 0; i < size_; ++i)
      if (items_[i] == label) return true;
    return false;
  }
  // Every label of *this is in `other`.
  bool subsetOf(const LabelSet& other) const {
    int j = 0;
    for (int i = 0; i < size_; ++i) {
      while (j < other.size_ && other.items_[j] < items_[i]) ++j;
      if (j == other.size_ || other.items_[j] != items_[i]) return false;
    }
    return true;
  }
  LabelSet intersection(const LabelSet& other) const {
    LabelSet out;
    for (int i = 0; i < size_; ++i)
      if (other.contains(items_[i])) out.items_[out.size_++] = items_[i];
    return out;
  }

  int size() const { return size_; }
  bool empty() const { return size_ == 0; }
  bool overflow() const { return overflow_; }
  std::int32_t operator[](int i) const { return items_[i]; }
  const std::int32_t* begin() const { return items_.data(); }
  const std::int32_t* end() const { return items_.data() + size_; }

  bool operator==(const LabelSet& o) const {
    if (size_ != o.size_ || overflow_ != o.overflow_) return false;
    for (int i = 0; i < size_; ++i)
      if (items_[i] != o.items_[i]) return false;
    return true;
  }
  bool operator<(const LabelSet& o) const {
    for (int i = 0; i < size_ && i < o.size_; ++i)
      if (items_[i] != o.items_[i]) return items_[i] < o.items_[i];
    return size_ < o.size_;
  }

  // "{1,4,7}" for reports and test messages.
  std::string toString() const {
    std::string s = "{";
    for (int i = 0; i < size_; ++i) s += (i ? "," : "") + std::to_string(items_[i]);
    return s + "}";
  }

private:
  std::array<std::int32_t, kCapacity> items_{};
  std::uint8_t size_ = 0;
  bool overflow_ = false;
};

}  // namespace vox::remesh
