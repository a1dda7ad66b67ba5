// The model format's byte primitives (serialize*.cpp) and the blocks its files share: little-endian
// integers, IEEE-754 binary64 reals, length-prefixed strings, vectors and matrices. Reader checks every
// length against the bytes left and keeps the first failure, so a corrupt model is an error, never UB.
#pragma once

#include <Eigen/Core>
#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "glimpse/features/methods.h"

namespace glimpse::serial {

class Writer {
 public:
  std::vector<uint8_t> bytes;
  template <class T>
  void uint(T v) {
    for (size_t i = 0; i < sizeof(T); ++i) bytes.push_back(static_cast<uint8_t>(static_cast<uint64_t>(v) >> (8 * i)));
  }
  void u8(uint8_t v) { uint(v); }
  void u32(uint32_t v) { uint(v); }
  void i32(int32_t v) { uint(static_cast<uint32_t>(v)); }
  void u64(uint64_t v) { uint(v); }
  void f64(double v) { uint(std::bit_cast<uint64_t>(v)); }
  void str(const std::string& s) {
    u32(static_cast<uint32_t>(s.size()));
    bytes.insert(bytes.end(), s.begin(), s.end());
  }
  void vec(const Eigen::VectorXd& v) {
    u32(static_cast<uint32_t>(v.size()));
    for (Eigen::Index i = 0; i < v.size(); ++i) f64(v[i]);
  }
  void mat(const Eigen::MatrixXd& m) {
    u32(static_cast<uint32_t>(m.rows()));
    u32(static_cast<uint32_t>(m.cols()));
    for (Eigen::Index r = 0; r < m.rows(); ++r)
      for (Eigen::Index c = 0; c < m.cols(); ++c) f64(m(r, c));
  }
  // The same layout with binary32 values: for a matrix whose values are binary32 already (a decision
  // stage's references that do not fit binary16), so nothing is lost, or where binary32 is enough (a
  // solver's start).
  void mat32(const Eigen::MatrixXd& m) {
    u32(static_cast<uint32_t>(m.rows()));
    u32(static_cast<uint32_t>(m.cols()));
    for (Eigen::Index r = 0; r < m.rows(); ++r)
      for (Eigen::Index c = 0; c < m.cols(); ++c) uint(std::bit_cast<uint32_t>(static_cast<float>(m(r, c))));
  }
  // The same layout with binary16 values, for a matrix whose values are binary16 already (a decision
  // stage's references, format 14 on): nothing is lost.
  void mat16(const Eigen::MatrixXd& m) {
    u32(static_cast<uint32_t>(m.rows()));
    u32(static_cast<uint32_t>(m.cols()));
    for (Eigen::Index r = 0; r < m.rows(); ++r)
      for (Eigen::Index c = 0; c < m.cols(); ++c)
        uint(Eigen::numext::bit_cast<uint16_t>(static_cast<Eigen::half>(static_cast<float>(m(r, c)))));
  }
};

class Reader {
 public:
  Reader(const uint8_t* p, size_t n) : p_(p), end_(p + n) {}
  bool failed() const { return failed_; }
  const std::string& why() const { return why_; }
  size_t left() const { return static_cast<size_t>(end_ - p_); }
  void fail(const std::string& why) {
    if (!failed_) why_ = why;
    failed_ = true;
  }
  bool need(size_t n, const char* what) {
    if (failed_) return false;
    if (left() < n) fail(std::string("truncated while reading ") + what);
    return !failed_;
  }
  template <class T>
  T uint(const char* what) {
    if (!need(sizeof(T), what)) return T{};
    uint64_t v = 0;
    for (size_t i = 0; i < sizeof(T); ++i) v |= static_cast<uint64_t>(p_[i]) << (8 * i);
    p_ += sizeof(T);
    return static_cast<T>(v);
  }
  uint8_t u8(const char* w) { return uint<uint8_t>(w); }
  uint32_t u32(const char* w) { return uint<uint32_t>(w); }
  int32_t i32(const char* w) { return static_cast<int32_t>(uint<uint32_t>(w)); }
  uint64_t u64(const char* w) { return uint<uint64_t>(w); }
  double f64(const char* w) { return std::bit_cast<double>(uint<uint64_t>(w)); }
  double f32(const char* w) { return std::bit_cast<float>(uint<uint32_t>(w)); }
  double f16(const char* w) { return static_cast<float>(Eigen::numext::bit_cast<Eigen::half>(uint<uint16_t>(w))); }
  std::string str(const char* what) {
    const uint32_t n = u32(what);
    if (!need(n, what)) return {};
    std::string s(reinterpret_cast<const char*>(p_), n);
    p_ += n;
    return s;
  }
  Eigen::VectorXd vec(const char* what) {
    const uint32_t n = u32(what);
    if (!need(size_t{n} * 8, what)) return {};
    Eigen::VectorXd v(n);
    for (uint32_t i = 0; i < n; ++i) v[i] = f64(what);
    return v;
  }
  // A matrix of binary64 values (mat), binary32 ones (mat32, bytes 4) or binary16 ones (mat16, bytes 2).
  Eigen::MatrixXd mat(const char* what, int value_bytes = 8) {
    const uint64_t rows = u32(what), cols = u32(what), bytes = static_cast<uint64_t>(value_bytes);
    if (cols && rows > left() / bytes / cols) {
      fail(std::string("truncated while reading ") + what);
      return {};
    }
    if (!need(rows * cols * bytes, what)) return {};
    Eigen::MatrixXd m(static_cast<Eigen::Index>(rows), static_cast<Eigen::Index>(cols));
    for (uint64_t r = 0; r < rows; ++r)
      for (uint64_t c = 0; c < cols; ++c)
        m(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c)) =
            bytes == 2 ? f16(what) : bytes == 4 ? f32(what) : f64(what);
    return m;
  }

 private:
  const uint8_t* p_;
  const uint8_t* end_;
  bool failed_ = false;
  std::string why_;
};

// CRC-32 (IEEE 802.3) of the bytes: the model's and the training set's checksum.
inline uint32_t crc32(const uint8_t* data, size_t n) {
  static const std::array<uint32_t, 256> table = [] {
    std::array<uint32_t, 256> t{};
    for (uint32_t i = 0; i < 256; ++i) {
      uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      t[i] = c;
    }
    return t;
  }();
  uint32_t c = 0xFFFFFFFFu;
  for (size_t i = 0; i < n; ++i) c = table[(c ^ data[i]) & 0xFF] ^ (c >> 8);
  return c ^ 0xFFFFFFFFu;
}

}  // namespace glimpse::serial

namespace glimpse {
struct Calibration;
struct ModelImpl;
struct TrainParams;
// The training parameters as (name, value) pairs (serialize_params.cpp). read_train_params sets every
// parameter it knows from the pairs read (a value the parameter cannot hold fails the reader) and
// returns all the pairs read, so the caller can tell which a model's writer knew.
void write_train_params(serial::Writer& w, const TrainParams& p);
std::map<std::string, double> read_train_params(serial::Reader& r, TrainParams& p);
// The calibration block (serialize_calibration.cpp); read_calibration needs the model's stages read.
void write_calibration(serial::Writer& w, const Calibration& c);
void read_calibration(serial::Reader& r, Calibration& c, uint32_t ncat, const ModelImpl& impl, uint32_t version);
// A method list: a u32 count, a u8 per method (serialize_impl.cpp).
void write_methods(serial::Writer& w, const std::vector<MethodId>& ms);
std::vector<MethodId> read_methods(serial::Reader& r);
// The trained part of a model (serialize_impl.cpp); then (format 8 on) a u8, 1: the novelty model follows
// (ModelImpl::novelty, the same layout, its own flag 0); then, but for the novelty model (`nested`), how
// novelty combines its evidence (format 9 on). read_impl reads a block of format `version`.
void write_impl(serial::Writer& w, const ModelImpl& m, bool nested);
std::shared_ptr<ModelImpl> read_impl(serial::Reader& r, uint32_t ncat, uint32_t version, bool nested);
}  // namespace glimpse
