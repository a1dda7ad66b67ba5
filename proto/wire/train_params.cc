#include "proto/wire/train_params.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "proto/wire/methods.h"
#include "proto/wire/model_names.h"

namespace glimpse::wire {
namespace {

using Parameters = v1::TrainParameters;

// A positive count of TrainParameters and the TrainParams field it sets.
struct CountField {
  const char* name;
  bool (Parameters::*has)() const;
  uint32_t (Parameters::*get)() const;
  void (Parameters::*set)(uint32_t);
  int& (*in)(TrainParams&);
};

const CountField kCounts[] = {
    {"bok_codebook_size", &Parameters::has_bok_codebook_size, &Parameters::bok_codebook_size,
     &Parameters::set_bok_codebook_size, [](TrainParams& p) -> int& { return p.bok_clusters; }},
    {"bog_keypoint_clusters", &Parameters::has_bog_keypoint_clusters, &Parameters::bog_keypoint_clusters,
     &Parameters::set_bog_keypoint_clusters, [](TrainParams& p) -> int& { return p.bog_keypoint_clusters; }},
    {"bog_volume_clusters", &Parameters::has_bog_volume_clusters, &Parameters::bog_volume_clusters,
     &Parameters::set_bog_volume_clusters, [](TrainParams& p) -> int& { return p.bog_volume_clusters; }},
    {"bog_pca_dims", &Parameters::has_bog_pca_dims, &Parameters::bog_pca_dims, &Parameters::set_bog_pca_dims,
     [](TrainParams& p) -> int& { return p.bog_pca_dims; }},
    {"kgh_keypoint_clusters", &Parameters::has_kgh_keypoint_clusters, &Parameters::kgh_keypoint_clusters,
     &Parameters::set_kgh_keypoint_clusters, [](TrainParams& p) -> int& { return p.kgh_clusters; }},
    {"kgh_distance_bins", &Parameters::has_kgh_distance_bins, &Parameters::kgh_distance_bins,
     &Parameters::set_kgh_distance_bins, [](TrainParams& p) -> int& { return p.kgh_distance_bins; }},
    {"centres_per_category", &Parameters::has_centres_per_category, &Parameters::centres_per_category,
     &Parameters::set_centres_per_category, [](TrainParams& p) -> int& { return p.decision.centres_per_category; }},
    {"neighbours", &Parameters::has_neighbours, &Parameters::neighbours, &Parameters::set_neighbours,
     [](TrainParams& p) -> int& { return p.decision.neighbours; }},
};

struct DecisionPair {
  DecisionRule rule;
  v1::DecisionKind proto;
};
constexpr DecisionPair kDecisions[] = {{DecisionRule::kNearestCentre, v1::DECISION_KIND_NEAREST_CENTRE},
                                       {DecisionRule::kCentres, v1::DECISION_KIND_CENTRES},
                                       {DecisionRule::kNearestNeighbours, v1::DECISION_KIND_NEAREST_NEIGHBOURS},
                                       {DecisionRule::kNearestReference, v1::DECISION_KIND_NEAREST_REFERENCE}};

Status CheckParameters(const Parameters& p) {
  if (p.has_support_radius_m() && !(std::isfinite(p.support_radius_m()) && p.support_radius_m() >= 0))
    return invalid_argument("support_radius_m must be a finite number >= 0 (0: automatic)");
  for (const CountField& f : kCounts)
    if ((p.*f.has)() && (p.*f.get)() == 0) return invalid_argument(std::string(f.name) + " must be positive");
  if (!v1::DecisionKind_IsValid(p.decision())) return invalid_argument("unknown decision kind");
  if (p.has_view_density() && !(std::isfinite(p.view_density()) && p.view_density() >= 0))
    return invalid_argument("view_density must be a finite number >= 0");
  return {};
}

Status CheckMethods(const v1::TrainHeader& header, TrainSpec& spec) {
  for (int m : header.methods()) {
    auto method = MethodFromProto(m);
    if (!method) return method.error();
    if (!*method) return invalid_argument("methods: METHOD_UNSPECIFIED is not a method");
    spec.methods.push_back(**method);
  }
  auto default_method = MethodFromProto(header.default_method());
  if (!default_method) return default_method.error();
  spec.default_method = *default_method;
  if (spec.default_method && !spec.methods.empty() &&
      std::find(spec.methods.begin(), spec.methods.end(), *spec.default_method) == spec.methods.end())
    return invalid_argument("default_method is not one of the methods to train");
  return {};
}

}  // namespace

Expected<TrainSpec> TrainSpecFromProto(const v1::TrainHeader& header) {
  if (Status s = ValidateModelName(header.model_name()); !s.ok()) return s.error();
  if (header.description().size() > kMaxDescriptionBytes)
    return invalid_argument("description is longer than " + std::to_string(kMaxDescriptionBytes) + " bytes");
  TrainSpec spec;
  if (Status s = CheckMethods(header, spec); !s.ok()) return s.error();
  if (Status s = CheckParameters(header.parameters()); !s.ok()) return s.error();
  spec.parameters = header.parameters();
  if (header.has_base()) {
    if (Status s = ValidateModelName(header.base().name()); !s.ok())
      return invalid_argument("base: " + s.error().message);
    if (!spec.methods.empty() || spec.default_method || header.parameters().ByteSizeLong() > 0)
      return invalid_argument("a model grown from a base keeps the base's methods and parameters: "
                              "send no methods, default_method or parameters with base");
    spec.base = BaseRef{header.base().name(), header.base().version()};
  }
  return spec;
}

Expected<TrainParams> ToTrainParams(const TrainSpec& spec) {
  TrainParams params;
  if (!spec.methods.empty()) params.methods = spec.methods;
  if (spec.default_method) {
    params.default_method = *spec.default_method;
  } else if (std::find(params.methods.begin(), params.methods.end(), params.default_method) == params.methods.end()) {
    params.default_method = params.methods.front();  // core's default (fusion) is not among those asked for
  }
  const Parameters& p = spec.parameters;
  if (p.has_support_radius_m()) params.features.surface.support_radius_m = static_cast<float>(p.support_radius_m());
  for (const CountField& f : kCounts) {
    if (!(p.*f.has)()) continue;
    const uint32_t v = (p.*f.get)();
    if (v > static_cast<uint32_t>(std::numeric_limits<int>::max()))
      return invalid_argument(std::string(f.name) + " is too large");
    f.in(params) = static_cast<int>(v);
  }
  for (const DecisionPair& d : kDecisions)
    if (d.proto == p.decision()) params.decision.kind = d.rule;  // unspecified: core's default
  if (p.has_seed()) params.seed = p.seed();
  if (p.has_normalise_histograms()) params.normalise_histograms = p.normalise_histograms();
  if (p.has_filter_scans()) params.filter_scans = p.filter_scans();
  return params;
}

v1::TrainParameters FromTrainParams(const TrainParams& params) {
  Parameters p;
  p.set_support_radius_m(params.features.surface.support_radius_m);
  TrainParams counts = params;  // the table's accessors write too
  for (const CountField& f : kCounts) (p.*f.set)(static_cast<uint32_t>(f.in(counts)));
  for (const DecisionPair& d : kDecisions)
    if (d.rule == params.decision.kind) p.set_decision(d.proto);
  p.set_seed(params.seed);
  p.set_normalise_histograms(params.normalise_histograms);
  p.set_filter_scans(params.filter_scans);
  return p;
}

}  // namespace glimpse::wire
