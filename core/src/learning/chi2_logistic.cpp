#include "glimpse/learning/chi2_logistic.h"

#include <linear.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <mutex>
#include <numbers>
#include <string>

namespace glimpse {

Eigen::VectorXd additive_chi2_features(const std::vector<Eigen::VectorXd>& histograms, int sample_steps,
                                       double sample_interval) {
  const int steps = std::max(1, sample_steps);
  Eigen::Index total = 0;
  for (const Eigen::VectorXd& h : histograms) total += h.size() * (2 * steps - 1);
  Eigen::VectorXd out = Eigen::VectorXd::Zero(total);
  Eigen::Index at = 0;
  for (const Eigen::VectorXd& h : histograms) {
    const Eigen::Index d = h.size();
    const double mass = h.cwiseMax(0.0).sum();
    for (Eigen::Index i = 0; i < d && mass > 0; ++i) {
      const double x = std::max(h[i], 0.0) / mass;
      if (x <= 0) continue;
      const double L = sample_interval;
      out[at + i] = std::sqrt(x * L);  // the kernel's spectrum at 0
      for (int j = 1; j < steps; ++j) {  // and at j L: sqrt(2 x L sech(pi j L)) (cos, sin)(j L log x)
        const double factor = std::sqrt(2 * x * L / std::cosh(std::numbers::pi * j * L));
        out[at + (2 * j - 1) * d + i] = factor * std::cos(j * L * std::log(x));
        out[at + 2 * j * d + i] = factor * std::sin(j * L * std::log(x));
      }
    }
    at += d * (2 * steps - 1);
  }
  return out;
}

namespace {

void quiet(const char*) {}

Status check_problem(const Eigen::MatrixXd& features, const std::vector<int>& labels, int categories,
                     const Chi2LogisticParams& params) {
  if (categories < 2) return invalid_argument("a logistic decision needs at least 2 categories");
  if (features.rows() != static_cast<Eigen::Index>(labels.size()) || features.rows() < 2 || features.cols() < 1)
    return invalid_argument("the logistic decision needs at least 2 labelled training rows");
  if (!(params.c > 0)) return invalid_argument("the logistic decision's C must be positive");
  if (!(params.tolerance > 0)) return invalid_argument("the logistic decision's tolerance must be positive");
  std::vector<int> seen(static_cast<size_t>(categories), 0);
  for (int l : labels) {
    if (l < 0 || l >= categories) return internal_error("a training label is out of range");
    seen[static_cast<size_t>(l)] = 1;
  }
  for (int c = 0; c < categories; ++c)
    if (!seen[static_cast<size_t>(c)]) return invalid_argument("category " + std::to_string(c) + " has no training row");
  return {};
}

// The problem in LIBLINEAR's sparse rows: 1-based indices, a bias feature (value 1) last, -1 ends a row;
// row r starts at nodes[starts[r]].
struct SparseRows {
  std::vector<size_t> starts;
  std::vector<feature_node> nodes;
};

// Rows counted, then written, in blocks shared among threads (each row to its own place); a block is
// read column by column, as the matrix is stored.
SparseRows sparse_rows(const Eigen::MatrixXd& features, int threads) {
  const int n = static_cast<int>(features.cols());
  const Eigen::Index rows_count = features.rows();
  const int fill_threads = threads > 0 ? threads : omp_get_max_threads();
  constexpr Eigen::Index kBlock = 256;
  const Eigen::Index blocks = (rows_count + kBlock - 1) / kBlock;
  SparseRows out;
  std::vector<size_t>& starts = out.starts;
  starts.assign(static_cast<size_t>(rows_count) + 1, 2);  // the bias and the end marker
  starts[0] = 0;
#pragma omp parallel for num_threads(fill_threads) schedule(static)
  for (Eigen::Index b = 0; b < blocks; ++b) {
    const Eigen::Index first = b * kBlock, last = std::min(rows_count, first + kBlock);
    for (int c = 0; c < n; ++c)
      for (Eigen::Index r = first; r < last; ++r) starts[static_cast<size_t>(r) + 1] += features(r, c) != 0;
  }
  for (size_t r = 0; r < static_cast<size_t>(rows_count); ++r) starts[r + 1] += starts[r];
  out.nodes.resize(starts.back());
  feature_node* nodes = out.nodes.data();
#pragma omp parallel for num_threads(fill_threads) schedule(static)
  for (Eigen::Index b = 0; b < blocks; ++b) {
    const Eigen::Index first = b * kBlock, last = std::min(rows_count, first + kBlock);
    feature_node* at[kBlock];
    for (Eigen::Index r = first; r < last; ++r) at[r - first] = nodes + starts[static_cast<size_t>(r)];
    for (int c = 0; c < n; ++c)
      for (Eigen::Index r = first; r < last; ++r)
        if (const double v = features(r, c); v != 0) *at[r - first]++ = {c + 1, v};
    for (Eigen::Index r = first; r < last; ++r) *at[r - first]++ = {n + 1, 1.0}, *at[r - first] = {-1, 0.0};
  }
  return out;
}

// Category k against the rest: its rows first, so LIBLINEAR takes it as its positive label (label index
// 0), as it does for the first category of a multi-class problem. Writes row k of the head's weights and
// bias; the reason when LIBLINEAR refuses or fails, empty otherwise.
std::string fit_one_against_rest(SparseRows& x, const std::vector<int>& labels, int k, int n,
                                 const parameter& param, const Chi2Logistic* start, Chi2Logistic& head) {
  std::vector<feature_node*> rows;
  std::vector<double> y;
  for (int positive = 1; positive >= 0; --positive)
    for (size_t r = 0; r < labels.size(); ++r)
      if ((labels[r] == k) == bool(positive))
        rows.push_back(x.nodes.data() + x.starts[r]), y.push_back(positive ? 1 : -1);
  std::vector<double> init;
  parameter own = param;
  if (start && start->weights.rows() == head.weights.rows() && start->weights.cols() == n) {
    init.resize(static_cast<size_t>(n) + 1);
    for (int f = 0; f < n; ++f) init[static_cast<size_t>(f)] = start->weights(k, f);
    init[static_cast<size_t>(n)] = start->bias[k];
    own.init_sol = init.data();
  }
  problem prob{};
  prob.l = static_cast<int>(rows.size());
  prob.n = n + 1;
  prob.y = y.data();
  prob.x = rows.data();
  prob.bias = 1;
  if (const char* why = check_parameter(&prob, &own)) return std::string("LIBLINEAR: ") + why;
  std::unique_ptr<model, void (*)(model*)> fitted(train(&prob, &own), [](model* m) { free_and_destroy_model(&m); });
  if (!fitted || get_nr_class(fitted.get()) != 2) return "LIBLINEAR trained no model";
  for (int f = 0; f < n; ++f) head.weights(k, f) = get_decfun_coef(fitted.get(), f + 1, 0);
  head.bias[k] = get_decfun_bias(fitted.get(), 0);
  return {};
}

}  // namespace

Expected<Chi2Logistic> fit_chi2_logistic(const Eigen::MatrixXd& features, const std::vector<int>& labels, int categories,
                                         const Chi2LogisticParams& params, int threads, const Chi2Logistic* start) {
  if (Status s = check_problem(features, labels, categories, params); !s.ok()) return s.error();
  static std::once_flag silenced;
  std::call_once(silenced, [] { set_print_string_function(&quiet); });
  const int n = static_cast<int>(features.cols());
  SparseRows x = sparse_rows(features, threads);
  parameter param{};
  param.solver_type = L2R_LR;
  param.eps = params.tolerance;
  param.C = params.c;

  Chi2Logistic head;
  head.sample_steps = params.sample_steps;
  head.sample_interval = params.sample_interval;
  head.weights = Eigen::MatrixXd::Zero(categories, n);
  head.bias = Eigen::VectorXd::Zero(categories);
  // One-vs-rest as LIBLINEAR's multi-class training does it, one binary problem per category, the
  // problems shared among threads (each writes its own row of weights: the same answer whatever the
  // thread count); two categories are one problem, negated.
  const int problems = categories == 2 ? 1 : categories;
  std::vector<std::string> failed(static_cast<size_t>(problems));
  const int workers = std::max(1, std::min(threads > 0 ? threads : omp_get_max_threads(), problems));
#pragma omp parallel for num_threads(workers) schedule(dynamic, 1)
  for (int k = 0; k < problems; ++k) failed[static_cast<size_t>(k)] = fit_one_against_rest(x, labels, k, n, param, start, head);
  for (const std::string& why : failed)
    if (!why.empty()) return internal_error(why);
  if (categories == 2) head.weights.row(1) = -head.weights.row(0), head.bias[1] = -head.bias[0];
  return head;
}

Chi2Logistic head_for_categories(const Chi2Logistic& head, const std::vector<std::string>& from,
                                 const std::vector<std::string>& to, const Chi2Logistic* others) {
  Chi2Logistic out;
  out.sample_steps = head.sample_steps;
  out.sample_interval = head.sample_interval;
  out.weights = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(to.size()), head.weights.cols());
  out.bias = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(to.size()));
  for (size_t k = 0; k < to.size(); ++k) {
    const auto at = std::find(from.begin(), from.end(), to[k]);
    const Eigen::Index row = at - from.begin(), to_row = static_cast<Eigen::Index>(k);
    if (at != from.end() && row < head.weights.rows() && row < head.bias.size()) {
      out.weights.row(to_row) = head.weights.row(row);
      out.bias[to_row] = head.bias[row];
    } else if (others && others->weights.rows() == out.weights.rows() && others->weights.cols() == out.weights.cols() &&
               others->bias.size() == out.bias.size()) {
      out.weights.row(to_row) = others->weights.row(to_row);
      out.bias[to_row] = others->bias[to_row];
    }
  }
  return out;
}

Eigen::VectorXd chi2_logistic_probabilities(const Chi2Logistic& head, const Eigen::VectorXd& features) {
  if (features.size() != head.weights.cols() || head.weights.rows() == 0) return {};
  const Eigen::VectorXd decision = head.weights * features + head.bias;
  Eigen::VectorXd p = (1.0 + (-decision.array()).exp()).inverse().matrix();
  const double total = p.sum();
  return total > 0 ? Eigen::VectorXd(p / total) : Eigen::VectorXd::Constant(p.size(), 1.0 / double(p.size()));
}

}  // namespace glimpse
