// One column of samples, owned (read from a file, computed) or borrowed from memory its owner keeps
// alive (a numpy array handed to the Python module), so that a record given in memory is read
// where it lies and never copied.
//
// Reading is a const std::vector<double>'s (size, [], data, begin/end, front/back), through any
// reference, and a column converts to std::span<const double>. Writing is explicit: owned() (or
// push_back, resize, ...) gives the owned vector, a borrowed column first making its own copy
// (copy on write), so borrowed memory is never changed and a read never copies.
//
// Relies on: the owner's memory staying unchanged while a column borrows it (the keep-alive handle
// holds it; whoever lends it documents that it must not be written meanwhile). Guarantees: moving a
// column never copies; copying a borrowed column shares the borrowed memory.
#pragma once

#include <algorithm>
#include <cstddef>
#include <initializer_list>
#include <memory>
#include <span>
#include <utility>
#include <vector>

namespace sidc {

class Column {
 public:
  using value_type = double;
  using size_type = std::size_t;
  using const_iterator = const double*;
  using iterator = const double*;

  Column() = default;
  Column(std::vector<double> values) : owned_(std::move(values)) {}  // NOLINT: a vector is a column
  Column(std::initializer_list<double> values) : owned_(values) {}
  Column(std::size_t n, double value) : owned_(n, value) {}
  template <class It>
  Column(It first, It last) : owned_(first, last) {}

  // A view of `values`, kept valid by `keep_alive` (released when the last column sharing it goes).
  static Column borrowed(std::span<const double> values, std::shared_ptr<const void> keep_alive) {
    Column c;
    c.borrowed_ = values;
    c.keep_alive_ = std::move(keep_alive);
    return c;
  }
  bool is_borrowed() const { return keep_alive_ != nullptr; }

  // Reading.
  const double* data() const { return is_borrowed() ? borrowed_.data() : owned_.data(); }
  std::size_t size() const { return is_borrowed() ? borrowed_.size() : owned_.size(); }
  bool empty() const { return size() == 0; }
  const double& operator[](std::size_t i) const { return data()[i]; }
  const double& front() const { return data()[0]; }
  const double& back() const { return data()[size() - 1]; }
  const double* begin() const { return data(); }
  const double* end() const { return data() + size(); }
  const double* cbegin() const { return begin(); }
  const double* cend() const { return end(); }
  operator std::span<const double>() const { return {data(), size()}; }  // NOLINT: a column is a span

  // Writing: the owned vector (a borrowed column copied into it first).
  std::vector<double>& owned() {
    if (is_borrowed()) {
      owned_.assign(borrowed_.begin(), borrowed_.end());
      borrowed_ = {};
      keep_alive_.reset();
    }
    return owned_;
  }
  void push_back(double x) { owned().push_back(x); }
  void pop_back() { owned().pop_back(); }
  void reserve(std::size_t n) { owned().reserve(n); }
  void resize(std::size_t n) { owned().resize(n); }
  void resize(std::size_t n, double x) { owned().resize(n, x); }
  void clear() { *this = Column(); }
  void shrink_to_fit() { owned().shrink_to_fit(); }
  void assign(std::size_t n, double x) { *this = Column(std::vector<double>(n, x)); }
  template <class It>
  void assign(It first, It last) {
    *this = Column(std::vector<double>(first, last));
  }
  template <class It>
  double* insert(const double* at, It first, It last) {
    const auto offset = at - data();
    auto& v = owned();
    return &*v.insert(v.begin() + offset, first, last);
  }

  // The values as a vector of their own: moved out when owned, copied when borrowed.
  std::vector<double> release() && {
    if (is_borrowed()) return {borrowed_.begin(), borrowed_.end()};
    return std::move(owned_);
  }

  // A copy of the values, whichever the column is.
  std::vector<double> to_vector() const { return {begin(), end()}; }

  friend bool operator==(const Column& a, const Column& b) { return std::equal(a.begin(), a.end(), b.begin(), b.end()); }
  friend bool operator==(const Column& a, const std::vector<double>& b) { return std::equal(a.begin(), a.end(), b.begin(), b.end()); }

 private:
  std::vector<double> owned_;
  std::span<const double> borrowed_;
  std::shared_ptr<const void> keep_alive_;
};

}  // namespace sidc
