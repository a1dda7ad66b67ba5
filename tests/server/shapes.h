// The service tests' tiny synthetic problem for the real recogniser: partial views of spheres, boxes and
// cylinders of a few sizes, and a Train call that sends them over gRPC.
#pragma once

#include <grpcpp/grpcpp.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "glimpse/learning/model.h"
#include "glimpse/v1/glimpse.grpc.pb.h"
#include "proto/wire/clouds.h"

namespace glimpse::server::testing {

// Surface samples (point, outward normal) of a shape centred at the origin.
struct Surfel {
  Vec3 p, n;
};

inline Vec3 RandomUnit(std::mt19937& rng) {
  std::normal_distribution<float> g(0, 1);
  Vec3 d(g(rng), g(rng), g(rng));
  return d.normalized();
}

inline std::vector<Surfel> Sphere(float r, int n, std::mt19937& rng) {
  std::vector<Surfel> s;
  for (int i = 0; i < n; ++i) {
    Vec3 d = RandomUnit(rng);
    s.push_back({r * d, d});
  }
  return s;
}

inline std::vector<Surfel> Box(Vec3 size, int n, std::mt19937& rng) {
  std::uniform_real_distribution<float> u(-0.5f, 0.5f);
  const float areas[3] = {size.y() * size.z(), size.x() * size.z(), size.x() * size.y()};
  const float total = areas[0] + areas[1] + areas[2];
  std::vector<Surfel> s;
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side)
      for (int i = 0; i < int(n * areas[axis] / total / 2); ++i) {
        Vec3 p(u(rng) * size.x(), u(rng) * size.y(), u(rng) * size.z()), normal = Vec3::Zero();
        p[axis] = (side ? 0.5f : -0.5f) * size[axis];
        normal[axis] = side ? 1.f : -1.f;
        s.push_back({p, normal});
      }
  return s;
}

inline std::vector<Surfel> Cylinder(float r, float h, int n, std::mt19937& rng) {
  std::uniform_real_distribution<float> u(0, 1);
  const float side_area = 2 * float(M_PI) * r * h, cap_area = float(M_PI) * r * r;
  std::vector<Surfel> s;
  for (int i = 0; i < n; ++i) {
    float pick = u(rng) * (side_area + 2 * cap_area), a = 2 * float(M_PI) * u(rng);
    if (pick < side_area) {
      Vec3 normal(std::cos(a), std::sin(a), 0);
      s.push_back({Vec3(r * normal.x(), r * normal.y(), (u(rng) - 0.5f) * h), normal});
    } else {
      float rr = r * std::sqrt(u(rng)), z = pick < side_area + cap_area ? h / 2 : -h / 2;
      s.push_back({Vec3(rr * std::cos(a), rr * std::sin(a), z), Vec3(0, 0, z > 0 ? 1.f : -1.f)});
    }
  }
  return s;
}

// A 2.5D view: the surfels facing a sensor 2 m away in a random direction (back-face culled).
inline Cloud View(const std::vector<Surfel>& surfels, std::mt19937& rng) {
  Vec3 dir = RandomUnit(rng);
  dir.z() = std::abs(dir.z()) + 0.3f;  // from above-ish
  const Vec3 sensor = 2.0f * dir.normalized();
  Cloud c;
  c.sensor = sensor;
  for (const Surfel& s : surfels)
    if (s.n.dot(sensor - s.p) > 0) c.points.push_back(s.p);
  return c;
}

inline TrainingCloud Sample(const std::string& category, int object, int view) {
  std::mt19937 rng(static_cast<unsigned>(1000 * object + 17 * view + category.size()));
  const float scale = 0.8f + 0.1f * float(object);
  std::vector<Surfel> surfels;
  if (category == "sphere") surfels = Sphere(0.25f * scale, 3000, rng);
  if (category == "box") surfels = Box(Vec3(0.5f, 0.35f, 0.25f) * scale, 3000, rng);
  if (category == "cylinder") surfels = Cylinder(0.15f * scale, 0.6f * scale, 3000, rng);
  return {category, category + std::to_string(object), View(surfels, rng)};
}

inline std::vector<TrainingCloud> Dataset() {
  std::vector<TrainingCloud> data;
  for (const char* category : {"box", "cylinder", "sphere"})
    for (int object = 0; object < 3; ++object)
      for (int view = 0; view < 2; ++view) data.push_back(Sample(category, object, view));
  return data;
}

// A Train call of `header` and `clouds`: its status and last progress message (the stored model's).
struct TrainResult {
  grpc::Status status;
  v1::TrainProgress last;
};
inline TrainResult TrainOverGrpc(v1::Glimpse::Stub& stub, const v1::TrainHeader& header,
                                 const std::vector<TrainingCloud>& clouds) {
  grpc::ClientContext ctx;
  auto stream = stub.Train(&ctx);
  v1::TrainRequest first;
  *first.mutable_header() = header;
  bool open = stream->Write(first);
  for (size_t i = 0; open && i < clouds.size(); ++i) {
    v1::TrainRequest req;
    req.mutable_cloud()->set_category(clouds[i].category);
    req.mutable_cloud()->set_object_id(clouds[i].object_id);
    req.mutable_cloud()->set_augmented(clouds[i].augmented);
    *req.mutable_cloud()->mutable_cloud() = wire::CloudToProto(clouds[i].cloud);
    open = stream->Write(req);
  }
  stream->WritesDone();
  TrainResult out;
  for (v1::TrainProgress p; stream->Read(&p);) out.last = p;
  out.status = stream->Finish();
  return out;
}

}  // namespace glimpse::server::testing
