#include "convert.h"

#include <google/protobuf/util/json_util.h>

#include <algorithm>
#include <cmath>

#include "proto/wire/methods.h"
#include "proto/wire/model_names.h"

namespace glimpse::server {

Expected<double> KnownAcceptanceFromProto(double known_acceptance) {
  if (known_acceptance >= 0 && known_acceptance <= 1) return known_acceptance;
  return invalid_argument("known_acceptance must be in (0, 1] (0: the model's default), not " +
                          std::to_string(known_acceptance));
}

Expected<ClassifyAsk> ClassifyAskFromProto(const v1::ModelRef& model, int method, double known_acceptance,
                                           std::string* method_log) {
  if (Status s = wire::ValidateModelName(model.name()); !s.ok()) return s.error();
  auto asked = wire::MethodFromProto(method);
  if (!asked) return asked.error();
  if (method_log) *method_log = wire::MethodName(*asked);
  auto acceptance = KnownAcceptanceFromProto(known_acceptance);
  if (!acceptance) return acceptance.error();
  return ClassifyAsk{*asked, *acceptance};
}

void ToProto(const ModelRecord& r, v1::ModelInfo* out) {
  out->set_id(static_cast<uint64_t>(r.id));
  out->set_name(r.name);
  out->set_version(r.version);
  out->set_is_default(r.is_default);
  out->mutable_created()->set_seconds(r.created_unix_ms / 1000);
  out->mutable_created()->set_nanos(static_cast<int32_t>(r.created_unix_ms % 1000) * 1'000'000);
  out->set_description(r.description);
  for (MethodId m : r.methods) out->add_methods(wire::MethodToProto(m));
  out->set_default_method(wire::MethodToProto(r.default_method));
  for (const std::string& c : r.stats.categories) out->add_categories(c);
  if (!r.params.empty()) {
    // Stored by this server from a valid message; unknown fields (a newer server's) are skipped.
    google::protobuf::util::JsonParseOptions options;
    options.ignore_unknown_fields = true;
    (void)google::protobuf::util::JsonStringToMessage(r.params, out->mutable_parameters(), options);
  }
  v1::TrainingStats* stats = out->mutable_stats();
  stats->set_clouds(r.stats.clouds);
  stats->set_objects(r.stats.objects);
  stats->set_keypoints(r.stats.keypoints);
  stats->set_seconds(r.stats.seconds);
  for (size_t i = 0; i < r.stats.categories.size(); ++i) {
    v1::CategoryCount* c = stats->add_categories();
    c->set_category(r.stats.categories[i]);
    if (i < r.stats.clouds_per_category.size()) c->set_clouds(r.stats.clouds_per_category[i]);
  }
  out->set_size_bytes(r.size_bytes);
  out->set_sha256(r.sha256);
  out->set_feature_version(r.feature_version);
  out->set_min_extent_m(r.stats.min_extent_m);
  out->set_max_extent_m(r.stats.max_extent_m);
  out->set_grown_from(r.grown_from);
  out->set_training_set_bytes(r.training_set_bytes);
}

namespace {
// Every category's score, and its calibrated probability where the model has them (`probabilities`
// empty: none).
template <class Msg>
void AddScores(const std::vector<std::string>& categories, const std::vector<double>& scores,
               const std::vector<double>& probabilities, int winner, Msg* out) {
  for (size_t i = 0; i < categories.size(); ++i) {
    v1::CategoryScore* s = out->add_scores();
    s->set_category(categories[i]);
    s->set_score(i < scores.size() ? scores[i] : 0.0);
    if (probabilities.size() == categories.size()) s->set_probability(probabilities[i]);
  }
  const bool decided = winner >= 0 && static_cast<size_t>(winner) < categories.size();
  out->set_winner_index(decided ? winner : -1);
  out->set_winner(decided ? categories[static_cast<size_t>(winner)] : std::string());
}
}  // namespace

void ToProto(const Classification& c, v1::ClassifyResponse* out) {
  out->set_method(wire::MethodToProto(c.method));
  AddScores(c.categories, c.scores, c.probabilities, c.winner, out);
  out->set_points(c.points);
  out->set_keypoints(c.keypoints);
  out->mutable_timings()->set_feature_ms(c.feature_ms);
  out->mutable_timings()->set_decision_ms(c.decision_ms);
  out->set_warning(c.warning);
  out->set_unknown(c.unknown);
  if (std::isfinite(c.novelty)) out->set_novelty(c.novelty);
  out->set_unknown_reason(c.unknown_reason);
  for (const std::string& edge : frame_edges(c.frame_cut)) out->add_frame_cut(edge);
}

void ToProto(const StreamDecision& d, v1::Decision* out) {
  out->set_chunk_index(d.chunk_index);
  out->set_points(d.points);
  out->set_keypoints(d.keypoints);
  AddScores(d.categories, d.scores, d.probabilities, d.winner, out);
  if (d.raw_scores.size() == d.categories.size())
    for (size_t i = 0; i < d.categories.size(); ++i) {
      v1::CategoryScore* s = out->add_raw_scores();
      s->set_category(d.categories[i]);
      s->set_score(d.raw_scores[i]);
    }
  out->set_final(d.final);
  out->set_category_changes(static_cast<uint32_t>(std::max(0, d.category_changes)));
  out->set_winner_held_chunks(static_cast<uint32_t>(std::max(0, d.winner_held_chunks)));
  out->set_settled(d.settled);
  out->set_confidence(d.confidence);
  out->set_unknown(d.unknown);
  if (std::isfinite(d.novelty)) out->set_novelty(d.novelty);
  out->set_unknown_reason(d.unknown_reason);
  for (const std::string& edge : frame_edges(d.frame_cut)) out->add_frame_cut(edge);
}

void ToProto(const ModelRecord& record, v1::ModelRef* out) {
  out->set_name(record.name);
  out->set_version(record.version);
}

}  // namespace glimpse::server
