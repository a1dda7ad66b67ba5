// Writes the deserializer's seed corpus: the payloads (the bytes between the 20-byte frame header and
// the CRC) of small models trained on two views of each zoo shape, one model per method mix, and one
// with half its clouds marked augmented (it carries a nested novelty model, format 8 on).
//   fuzz_make_model_seeds OUT_DIR
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "glimpse/learning/model.h"
#include "glimpse/learning/train_params.h"
#include "glimpse/views/sampling.h"
#include "glimpse/views/hidden_point_removal.h"
#include "glimpse/views/zoo.h"

int main(int argc, char** argv) {
  using namespace glimpse;
  if (argc != 2) {
    std::fprintf(stderr, "usage: fuzz_make_model_seeds OUT_DIR\n");
    return 2;
  }
  ZooOptions zoo;
  zoo.target_vertices = 1500;
  // Two views of each of `objects` zoo objects per category.
  const auto views = [&](size_t objects) {
    std::vector<TrainingCloud> data;
    for (const LabelledMesh& m : make_zoo(objects, 3, zoo)) {
      const Cloud full = mesh_vertices(m.mesh);
      const auto cameras = paper_viewpoints(full.points);
      for (size_t v : {size_t{0}, size_t{3}})
        data.push_back({m.category, m.category + "/" + std::to_string(m.seed), hidden_point_removal(full.points, cameras[v])});
    }
    return data;
  };
  struct Mix {
    const char* name;
    std::vector<MethodId> methods;
    MethodId default_method;
    bool augmented = false;  // mark each object's second view augmented: the model nests a novelty model
  };
  const Mix mixes[] = {{"bok", {MethodId::kBoK}, MethodId::kBoK},
                       {"esf", {MethodId::kESF}, MethodId::kESF},
                       {"vfh-kgh", {MethodId::kVFH, MethodId::kKGH}, MethodId::kKGH},
                       {"fusion", {MethodId::kBoK, MethodId::kKGH, MethodId::kFusion}, MethodId::kFusion},
                       {"fusion-novelty", {MethodId::kBoK, MethodId::kKGH, MethodId::kFusion}, MethodId::kFusion, true}};
  std::filesystem::create_directories(argv[1]);
  for (const Mix& mix : mixes) {
    TrainParams p;
    p.methods = mix.methods;
    p.default_method = mix.default_method;
    p.fusion_of = {MethodId::kBoK, MethodId::kKGH};  // small histograms: small seeds
    p.bok_clusters = 2;
    p.bog_keypoint_clusters = 2;
    p.bog_volume_clusters = 1;
    p.bog_pca_dims = 2;
    p.kgh_clusters = 2;
    p.kgh_distance_bins = 2;
    p.seed = 1;
    p.partial_prefixes = {0.5};  // one prefix per view: seeds small enough for the fuzzer's -max_len
    // The novelty model is calibrated on held-out objects: it needs a few of each category.
    std::vector<TrainingCloud> clouds = views(mix.augmented ? 3 : 1);
    for (size_t i = 1; i < clouds.size(); i += 2) clouds[i].augmented = mix.augmented;
    auto model = train(clouds, p);
    if (!model) {
      std::fprintf(stderr, "%s: %s\n", mix.name, model.error().message.c_str());
      return 1;
    }
    if (mix.augmented && &novelty_calibration(*model) == &calibration(*model)) {
      std::fprintf(stderr, "%s: no novelty model was kept\n", mix.name);
      return 1;
    }
    const std::vector<uint8_t> bytes = serialize(*model);
    const std::string path = std::string(argv[1]) + "/" + mix.name;
    std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(bytes.data() + 20),
                                                static_cast<std::streamsize>(bytes.size() - 24));
    std::printf("%s: %zu payload bytes\n", path.c_str(), bytes.size() - 24);
  }
  return 0;
}
