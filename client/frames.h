// A folder of frames as a scanner records them: one cloud file (.pcd, .ply, .xyz, ...) per frame, each
// seen from its own sensor position. `glimpse stream --frames DIR` streams them in order, one chunk per
// frame (or several, at most chunk_points each, every one with the frame's sensor), so the server fuses
// views from several positions, each frame's points facing its own sensor.
#pragma once

#include <string>
#include <vector>

#include "glimpse/cloud.h"
#include "glimpse/expected.h"

namespace glimpse::client {

// "frame2" < "frame10": names compare with their digit runs as numbers, then as text.
bool NaturalLess(const std::string& a, const std::string& b);

// The frames of DIR in natural name order (hidden files and other extensions skipped). Each frame's
// sensor is its file's (a PCD VIEWPOINT or a "glimpse_sensor x y z" comment), or its line of an optional
// DIR/poses.csv, which wins:
//   file,x,y,z                 the points are in the common frame; the sensor was at (x, y, z)
//   file,x,y,z,qw,qx,qy,qz     the points are in the sensor's own frame; the pose (a unit quaternion and
//                              the sensor's position) takes them into the common frame (p' = R p + t)
// The common frame is the service's: metres, +z up. Errors (naming the file and line): no frame, a frame
// without a sensor, a mesh, a bad or unknown poses.csv line, a non-unit quaternion.
Expected<std::vector<Cloud>> LoadFrames(const std::string& dir);

// Each frame cut into chunks of at most chunk_points points (0: one chunk per frame), in order, each
// with its frame's sensor; empty frames are sent as empty chunks (the scanner saw nothing).
std::vector<Cloud> FrameChunks(const std::vector<Cloud>& frames, size_t chunk_points);

}  // namespace glimpse::client
