// glimpse scene's table, JSON and SVG top view, and a tracking stream's target in the decision lines.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "client/render.h"
#include "client/render_scene.h"

namespace glimpse::client {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;

void Set(v1::Vec3* v, float x, float y, float z) { v->set_x(x), v->set_y(y), v->set_z(z); }

// A chair found 1.2 m away and an object too small to classify.
v1::ClassifySceneResponse MakeScene() {
  v1::ClassifySceneResponse r;
  r.mutable_model()->set_name("rooms");
  r.mutable_model()->set_version(2);
  r.set_method(v1::METHOD_FUSION);
  r.set_frame_points(1000);
  r.set_segment_ms(30);
  r.set_total_ms(80);
  v1::ScenePlane* floor = r.add_planes();
  Set(floor->mutable_normal(), 0, 0, 1);
  floor->set_points(600);
  v1::SceneObject* chair = r.add_objects();
  Set(chair->mutable_box_min(), 0, 1, 0);
  Set(chair->mutable_box_max(), 0.5f, 1.4f, 0.8f);
  Set(chair->mutable_centroid(), 0.25f, 1.2f, 0.4f);
  chair->set_range_m(1.2f);
  chair->set_points(300);
  chair->add_indices(0), chair->add_indices(10);
  v1::ClassifyResponse* answer = chair->mutable_result()->mutable_response();
  for (auto [c, s] : {std::pair{"chair", 0.8}, {"table", 0.2}}) {
    v1::CategoryScore* score = answer->add_scores();
    score->set_category(c);
    score->set_score(s);
  }
  answer->set_winner("chair");
  answer->set_winner_index(0);
  answer->set_novelty(1.5);
  v1::SceneObject* small = r.add_objects();
  Set(small->mutable_box_min(), 1, 2, 0);
  Set(small->mutable_box_max(), 1.1f, 2.1f, 0.1f);
  Set(small->mutable_centroid(), 1.05f, 2.05f, 0.05f);
  small->set_range_m(2.3f);
  small->set_points(210);
  small->mutable_result()->set_code(3);
  small->mutable_result()->set_message("object 1: too few points");
  return r;
}

TEST(RenderScene, TableHasARowPerObjectWithItsBoxOrItsStatus) {
  const std::string table = SceneTable(MakeScene());
  EXPECT_THAT(table, HasSubstr("WINNER"));
  EXPECT_THAT(table, HasSubstr("chair"));
  EXPECT_THAT(table, HasSubstr("0.800"));
  EXPECT_THAT(table, HasSubstr("0.50x0.40x0.80"));
  EXPECT_THAT(table, HasSubstr("0.25,1.20,0.40"));
  EXPECT_THAT(table, HasSubstr("INVALID_ARGUMENT: object 1: too few points"));
  EXPECT_EQ(LineCount(table), 3);
  EXPECT_THAT(table, Not(HasSubstr("CUT BY FRAME")));
}

TEST(RenderScene, JsonHasPlanesAndEveryObjectsAnswerOrError) {
  const std::string json = SceneJson("desk.pcd", MakeScene());
  EXPECT_EQ(json.front(), '{');
  EXPECT_EQ(json.back(), '}');
  EXPECT_THAT(json, HasSubstr("\"file\":\"desk.pcd\",\"model\":\"rooms\",\"version\":2,\"method\":\"fusion\""));
  EXPECT_THAT(json, HasSubstr("\"planes\":[{\"normal\":[0,0,1],\"offset\":0,\"points\":600}]"));
  EXPECT_THAT(json, HasSubstr("{\"object\":1,\"box_min\":[0,1,0],\"box_max\":[0.5,1.4,0.8]"));
  EXPECT_THAT(json, HasSubstr("\"winner\":\"chair\""));
  EXPECT_THAT(json, HasSubstr("\"object\":2,"));
  EXPECT_THAT(json, HasSubstr("\"error\":{\"code\":\"INVALID_ARGUMENT\",\"message\":\"object 1: too few points\"}"));
  EXPECT_EQ(std::count(json.begin(), json.end(), '{'), std::count(json.begin(), json.end(), '}'));
}

TEST(RenderScene, SvgDrawsEachBoxLabelledOverThinnedPoints) {
  Points frame;
  for (int i = 0; i < 1000; ++i) frame.push_back(Vec3(0.001f * float(i), 1.f + 0.001f * float(i), 0));
  const std::string svg = SceneSvg("a <desk> & more", MakeScene(), frame, Vec3(0, 0, 1), 100);
  EXPECT_EQ(svg.rfind("<svg", 0), 0u);
  EXPECT_THAT(svg, HasSubstr("</svg>"));
  EXPECT_THAT(svg, HasSubstr(">1 chair</text>"));
  EXPECT_THAT(svg, HasSubstr(">2 INVALID_ARGUMENT</text>"));
  EXPECT_THAT(svg, HasSubstr("a &lt;desk&gt; &amp; more"));
  size_t rects = 0, circles = 0;
  for (size_t at = 0; (at = svg.find("<rect", at)) != std::string::npos; ++at) ++rects;
  for (size_t at = 0; (at = svg.find("<circle", at)) != std::string::npos; ++at) ++circles;
  EXPECT_EQ(rects, 3u);  // the background and two boxes
  EXPECT_EQ(circles, 101u);  // every 10th point and the sensor
  // Points 0 and 10 are the chair's, drawn in its box's colour; the others grey.
  size_t chair_points = 0;
  for (size_t at = 0; (at = svg.find("r=\"1\" fill=\"#d62728\"", at)) != std::string::npos; ++at) ++chair_points;
  EXPECT_EQ(chair_points, 2u);
  EXPECT_THAT(svg, HasSubstr("r=\"1\" fill=\"#c8c8c8\""));
}

TEST(RenderScene, ATrackingStreamSaysWhereTheTargetIs) {
  v1::Decision d;
  d.set_winner("chair");
  d.set_winner_index(-1);
  d.mutable_tracked()->set_found(true);
  d.mutable_tracked()->set_objects(3);
  Set(d.mutable_tracked()->mutable_object()->mutable_centroid(), 0.1f, 1.25f, 0.4f);
  EXPECT_THAT(DecisionLine(d, 5), HasSubstr(" target at 0.10,1.25,0.40 (3 objects)"));
  EXPECT_THAT(DecisionJson(d, 5), HasSubstr(",\"tracked\":{\"found\":true,\"objects\":3,\"centroid\":[0.1,1.25,0.4]"));
  EXPECT_THAT(DecisionPanel(d, 5, ""), HasSubstr("target at 0.10,1.25,0.40"));
  d.mutable_tracked()->Clear();
  d.mutable_tracked()->set_not_found("the target left the view");
  EXPECT_THAT(DecisionLine(d, 5), HasSubstr(" target not found (the target left the view)"));
  EXPECT_THAT(DecisionJson(d, 5), HasSubstr("\"found\":false,\"objects\":0,\"not_found\":\"the target left the view\"}"));
  d.clear_tracked();
  EXPECT_THAT(DecisionLine(d, 5), Not(HasSubstr("target")));
}

}  // namespace
}  // namespace glimpse::client
