#include <gtest/gtest.h>

#include <cmath>

#include "client/render.h"

namespace glimpse::client {
namespace {

// Display cells of a UTF-8 string (each code point one cell).
size_t Cells(const std::string& s) {
  size_t n = 0;
  for (char c : s) n += (c & 0xC0) != 0x80;
  return n;
}

v1::Decision MakeDecision() {
  v1::Decision d;
  d.set_chunk_index(2);
  d.set_points(1234);
  d.set_keypoints(17);
  for (auto [c, s] : {std::pair{"human", 0.1}, {"chair", 0.82}, {"table", 0.3}}) {
    auto* score = d.add_scores();
    score->set_category(c);
    score->set_score(s);
  }
  for (auto [c, s] : {std::pair{"human", 0.2}, {"chair", 0.7}, {"table", 0.1}}) {
    auto* score = d.add_raw_scores();
    score->set_category(c);
    score->set_score(s);
  }
  d.set_winner("chair");
  d.set_winner_index(1);
  d.set_category_changes(1);
  d.set_winner_held_chunks(2);
  d.set_confidence(0.41);
  d.mutable_model()->set_name("zoo");
  d.mutable_model()->set_version(3);
  d.set_method(v1::METHOD_FUSION);
  d.set_latency_ms(12.5);
  return d;
}

ClassifyRow MakeRow(const std::string& file) {
  ClassifyRow row{file, {}};
  row.response.mutable_model()->set_name("zoo");
  row.response.mutable_model()->set_version(1);
  row.response.set_method(v1::METHOD_BOK);
  for (auto [c, s] : {std::pair{"human", 0.125}, {"chair", 0.875}}) {
    auto* score = row.response.add_scores();
    score->set_category(c);
    score->set_score(s);
  }
  row.response.set_winner("chair");
  row.response.set_winner_index(1);
  row.response.set_points(900);
  row.response.set_keypoints(12);
  row.response.mutable_timings()->set_total_ms(4.25);
  return row;
}

TEST(Bar, AlwaysExactlyWidthCells) {
  for (double f : {0.0, 0.01, 0.3, 0.5, 0.99, 1.0, 1.7, -0.5, std::nan("")})
    for (int w : {1, 7, 30}) EXPECT_EQ(Cells(Bar(f, w)), size_t(w)) << f << " " << w;
  EXPECT_EQ(Bar(0.5, 4), "██  ");
  EXPECT_EQ(Bar(1.0, 3), "███");
  EXPECT_EQ(Bar(0.0, 3), "   ");
  EXPECT_EQ(Bar(0.5, 1), "▌");  // half a cell: four eighths
  EXPECT_EQ(Bar(1.0 / 8, 1), "▏");
  EXPECT_EQ(Bar(0.5, 0), "");
}

TEST(Render, ScoresBytesAndTimestamps) {
  EXPECT_EQ(Score(0.8199), "0.820");
  EXPECT_EQ(Score(std::nan("")), "nan");
  EXPECT_EQ(FormatBytes(512), "512 B");
  EXPECT_EQ(FormatBytes(1536), "1.5 KiB");
  EXPECT_EQ(FormatBytes(3u << 20), "3.0 MiB");
  google::protobuf::Timestamp t;
  EXPECT_EQ(FormatTimestamp(t), "-");
  t.set_seconds(1700000000);
  EXPECT_EQ(FormatTimestamp(t), "2023-11-14 22:13:20Z");
}

TEST(Render, JsonStringEscapes) {
  EXPECT_EQ(JsonString("plain"), "\"plain\"");
  EXPECT_EQ(JsonString("a\"b\\c\nd\x01"), "\"a\\\"b\\\\c\\nd\\u0001\"");
  EXPECT_EQ(JsonString(""), "\"\"");
}

TEST(Render, TableAlignsColumns) {
  EXPECT_EQ(Table({{"A", "BB"}, {"ccc", "d"}}), "A    BB\nccc  d\n");
  EXPECT_EQ(Table({}), "");
}

TEST(Render, ClassifyTableHasAColumnPerCategory) {
  const std::string table = ClassifyTable({MakeRow("a.ply"), MakeRow("longer-name.pcd")});
  EXPECT_EQ(table,
            "FILE             WINNER  human  chair  POINTS  KEYPOINTS  MS\n"
            "a.ply            chair   0.125  0.875  900     12         4.2\n"
            "longer-name.pcd  chair   0.125  0.875  900     12         4.2\n");
}

TEST(Render, ClassifyJsonIsOneObjectWithScoresByCategory) {
  EXPECT_EQ(ClassifyJson(MakeRow("dir/\"x\".ply")),
            "{\"file\":\"dir/\\\"x\\\".ply\",\"model\":\"zoo\",\"version\":1,\"method\":\"bok\",\"winner\":\"chair\","
            "\"scores\":{\"human\":0.125,\"chair\":0.875},\"points\":900,\"keypoints\":12,\"total_ms\":4.25,"
            "\"warning\":\"\",\"unknown\":false,\"novelty\":null,\"unknown_reason\":\"\",\"frame_cut\":[]}");
  ClassifyRow warned = MakeRow("mm.ply");
  warned.response.set_warning("the cloud spans 1.7e+03 m: millimetres?");
  EXPECT_NE(ClassifyJson(warned).find(",\"warning\":\"the cloud spans 1.7e+03 m: millimetres?\","), std::string::npos);
}

// Where the camera's frame cuts an object: a column when any answer has a cut, and a JSON list.
TEST(Render, TheEdgesTheFrameCutsAreShownWhereThereAreAny) {
  ClassifyRow cut = MakeRow("close.pcd");
  cut.response.add_frame_cut("top");
  cut.response.add_frame_cut("bottom");
  EXPECT_EQ(ClassifyTable({cut, MakeRow("far.pcd")}),
            "FILE       WINNER  human  chair  CUT BY FRAME  POINTS  KEYPOINTS  MS\n"
            "close.pcd  chair   0.125  0.875  top,bottom    900     12         4.2\n"
            "far.pcd    chair   0.125  0.875  -             900     12         4.2\n");
  EXPECT_NE(ClassifyJson(cut).find(",\"frame_cut\":[\"top\",\"bottom\"]}"), std::string::npos) << ClassifyJson(cut);
}

// A calibrated answer shows its probabilities where it would show scores; JSON gives both.
TEST(Render, CalibratedAnswersShowProbabilities) {
  ClassifyRow row = MakeRow("p.ply");
  row.response.mutable_scores(0)->set_probability(0.02);
  row.response.mutable_scores(1)->set_probability(0.98);
  EXPECT_EQ(ClassifyTable({row}),
            "FILE   WINNER  human  chair  POINTS  KEYPOINTS  MS\n"
            "p.ply  chair   0.020  0.980  900     12         4.2\n");
  EXPECT_NE(ClassifyJson(row).find("\"scores\":{\"human\":0.125,\"chair\":0.875},\"probabilities\":{\"human\":0.02,"
                                   "\"chair\":0.98},"),
            std::string::npos)
      << ClassifyJson(row);
}

// "None of these": the winner stays the closest known category, shown beside the word unknown.
TEST(Render, UnknownAnswersNameTheClosestCategory) {
  ClassifyRow known = MakeRow("chair.ply");
  known.response.set_novelty(0.93);
  ClassifyRow unknown = MakeRow("bike.ply");
  unknown.response.set_unknown(true);
  unknown.response.set_novelty(2.456);
  unknown.response.set_unknown_reason("novelty 2.46 above 1.80");
  EXPECT_EQ(ClassifyTable({known, unknown}),
            "FILE       WINNER                          human  chair  NOVELTY  POINTS  KEYPOINTS  MS\n"
            "chair.ply  chair                           0.125  0.875  0.93     900     12         4.2\n"
            "bike.ply   unknown (closest: chair 0.875)  0.125  0.875  2.46     900     12         4.2\n");
  EXPECT_NE(ClassifyJson(unknown).find(",\"unknown\":true,\"novelty\":2.456,\"unknown_reason\":\"novelty 2.46 above 1.80\",\"frame_cut\":[]}"),
            std::string::npos)
      << ClassifyJson(unknown);
  v1::Decision d = MakeDecision();
  d.set_unknown(true);
  d.set_novelty(2.5);
  d.set_unknown_reason("novelty 2.50 above 2.00");
  EXPECT_EQ(DecisionLine(d, 20),
            "chunk 3/20 points 1234 keypoints 17 winner unknown (closest: chair 0.820) changes 1 settled no "
            "confidence 0.41 novelty 2.50");
  const std::string panel = DecisionPanel(d, 20, "chair", 10);
  EXPECT_NE(panel.find("winner unknown (closest: chair 0.820)"), std::string::npos) << panel;
  EXPECT_NE(panel.find("unknown: novelty 2.50 above 2.00"), std::string::npos) << panel;
  EXPECT_NE(DecisionJson(d, 20).find(",\"unknown\":true,\"novelty\":2.5,\"unknown_reason\":\"novelty 2.50 above 2.00\",\"frame_cut\":[]}"),
            std::string::npos);
}

TEST(Render, ClassifyErrorJsonHasTheFileAndTheStatus) {
  EXPECT_EQ(ClassifyErrorJson("a/\"b\".ply", "NOT_FOUND", "cannot open: No such file"),
            "{\"file\":\"a/\\\"b\\\".ply\",\"error\":{\"code\":\"NOT_FOUND\",\"message\":\"cannot open: No such file\"}}");
}

TEST(Render, DecisionLineIsTheDocumentedPlainFormat) {
  EXPECT_EQ(DecisionLine(MakeDecision(), 20),
            "chunk 3/20 points 1234 keypoints 17 winner chair 0.820 changes 1 settled no confidence 0.41");
  v1::Decision empty;
  empty.set_winner_index(-1);
  EXPECT_EQ(DecisionLine(empty, 5), "chunk 1/5 points 0 keypoints 0 winner - changes 0 settled no confidence 0.00");
  // A method that uses no keypoints (and found none) does not print a keypoint count.
  v1::Decision global = MakeDecision();
  global.set_keypoints(0);
  EXPECT_EQ(DecisionLine(global, 20), "chunk 3/20 points 1234 winner chair 0.820 changes 1 settled no confidence 0.41");
  global.set_method(v1::METHOD_BOK);
  EXPECT_EQ(DecisionLine(global, 20),
            "chunk 3/20 points 1234 keypoints 0 winner chair 0.820 changes 1 settled no confidence 0.41");
  v1::Decision final = MakeDecision();
  final.set_final(true);
  EXPECT_EQ(DecisionLine(final, 20),
            "final points 1234 keypoints 17 winner chair 0.820 changes 1 settled no confidence 0.41");
  EXPECT_NE(DecisionPanel(final, 20, "chair", 10).find("final (the whole scan, as Classify)"), std::string::npos);
}

TEST(Render, DecisionPanelMarksWinnerAndAChange) {
  const std::string panel = DecisionPanel(MakeDecision(), 20, "table", 10);
  EXPECT_EQ(LineCount(panel), 5);  // header, winner, three categories
  EXPECT_NE(panel.find("chunk 3/20"), std::string::npos);
  EXPECT_NE(panel.find("model zoo:3 (fusion)"), std::string::npos);
  EXPECT_NE(panel.find("winner chair 0.820   (was table)"), std::string::npos);
  EXPECT_NE(panel.find("> chair"), std::string::npos);
  EXPECT_NE(panel.find("  human  "), std::string::npos);
  EXPECT_EQ(DecisionPanel(MakeDecision(), 20, "chair", 10).find("(was"), std::string::npos);
  v1::Decision undecided;
  undecided.set_winner_index(-1);
  EXPECT_NE(DecisionPanel(undecided, 4, "", 10).find("winner -"), std::string::npos);
}

TEST(Render, DecisionJson) {
  EXPECT_EQ(DecisionJson(MakeDecision(), 20),
            "{\"chunk\":3,\"chunks\":20,\"points\":1234,\"keypoints\":17,\"winner\":\"chair\","
            "\"scores\":{\"human\":0.1,\"chair\":0.82,\"table\":0.3},\"raw_scores\":{\"human\":0.2,\"chair\":0.7,"
            "\"table\":0.1},\"final\":false,\"changes\":1,\"held\":2,\"settled\":false,"
            "\"confidence\":0.41,\"model\":\"zoo\",\"version\":3,\"method\":\"fusion\",\"latency_ms\":12.5,"
            "\"unknown\":false,\"novelty\":null,\"unknown_reason\":\"\",\"frame_cut\":[]}");
}

TEST(Render, TrainingProgress) {
  v1::TrainProgress p;
  p.set_stage("features");
  p.set_stage_done(12);
  p.set_stage_total(30);
  p.set_clouds_received(30);
  p.set_percent(43.4);
  const std::string bar = ProgressBar(p, 10);
  EXPECT_EQ(bar.substr(0, 1), "[");
  EXPECT_NE(bar.find("]  43%  features 12/30"), std::string::npos) << bar;
  EXPECT_EQ(ProgressLine(p), "train: 43% features 12/30 (clouds 30)");
  p.set_stage("receiving");
  EXPECT_EQ(ProgressLine(p), "train: 43% receiving 30 clouds (clouds 30)");
  p.set_stage("features");
  p.set_seconds_left(41.6);  // the server's estimate, when it has one
  EXPECT_EQ(ProgressLine(p), "train: 43% features 12/30 (clouds 30), about 42 s left");
  EXPECT_NE(ProgressBar(p, 10).find("features 12/30, about 42 s left"), std::string::npos) << ProgressBar(p, 10);
  p.set_seconds_left(431);
  EXPECT_EQ(ProgressLine(p), "train: 43% features 12/30 (clouds 30), about 7 min left");
  p.set_percent(100);
  p.set_seconds_left(0);
  EXPECT_NE(ProgressBar(p, 10).find("██████████] 100%"), std::string::npos);
}

v1::ModelInfo MakeModel() {
  v1::ModelInfo m;
  m.set_name("zoo");
  m.set_version(2);
  m.set_is_default(true);
  m.add_methods(v1::METHOD_BOK);
  m.add_methods(v1::METHOD_FUSION);
  m.set_default_method(v1::METHOD_FUSION);
  m.add_categories("human");
  m.add_categories("chair");
  m.mutable_stats()->set_clouds(60);
  m.mutable_stats()->set_keypoints(1234);
  m.mutable_stats()->set_seconds(12.34);
  m.set_size_bytes(2048);
  return m;
}

TEST(Render, TrainSummaryAndModelDetails) {
  EXPECT_EQ(TrainSummary(MakeModel()), "trained zoo:2 (default): 2 categories, 60 clouds, 1234 keypoints, 12.3 s, 2.0 KiB");
  const std::string details = ModelDetails(MakeModel());
  EXPECT_NE(details.find("methods:      bok,fusion (default fusion)"), std::string::npos) << details;
  EXPECT_NE(details.find("categories:   human, chair"), std::string::npos) << details;
  EXPECT_NE(details.find("version:      2 (default)"), std::string::npos) << details;
  v1::ModelInfo global = MakeModel();  // no keypoint method: nothing to say of keypoints
  global.set_methods(0, v1::METHOD_USH);
  global.mutable_stats()->set_keypoints(0);
  EXPECT_EQ(TrainSummary(global), "trained zoo:2 (default): 2 categories, 60 clouds, 12.3 s, 2.0 KiB");
  EXPECT_NE(ModelDetails(global).find("60 clouds of 0 objects, 12.3 s"), std::string::npos) << ModelDetails(global);
}

TEST(Render, ModelsTable) {
  v1::ListModelsResponse list;
  EXPECT_EQ(ModelsTable(list), "no models\n");
  *list.add_models() = MakeModel();
  const std::string table = ModelsTable(list);
  EXPECT_EQ(LineCount(table), 2);
  EXPECT_EQ(table.rfind("NAME  VERSION  DEFAULT  CREATED  METHODS     CATEGORIES  CLOUDS  SIZE\n", 0), 0u) << table;
  EXPECT_NE(table.find("zoo   2        *        -        bok,fusion  2           60      2.0 KiB"), std::string::npos)
      << table;
}

TEST(Render, ModelJsonUsesProtoFieldNamesOnOneLine) {
  const std::string json = ModelJson(MakeModel());
  EXPECT_EQ(LineCount(json), 0);
  EXPECT_NE(json.find("\"name\":\"zoo\""), std::string::npos) << json;
  EXPECT_NE(json.find("\"is_default\":true"), std::string::npos) << json;
  EXPECT_NE(json.find("\"default_method\":\"METHOD_FUSION\""), std::string::npos) << json;
}

}  // namespace
}  // namespace glimpse::client
