// Reading meshes and point clouds from the formats users have (OFF, OBJ, PLY, STL, PCD, XYZ) and writing
// clouds back. Hand-written parsers, and PCL's reader (inside the .cpp) for the LZF body of a PCD's DATA
// binary_compressed: no PCL types, no exceptions, nothing on stderr, bounded allocations.
//
// Format is chosen by extension (case-insensitive). Malformed input gives an Error (code kDataLoss,
// kNotFound for a missing file, kInvalidArgument for an unknown extension) whose message starts with
// the path and names the line ("file.off:12: ...") for text or the byte offset for binary data.
// Counts larger than the file could hold, or above 100M points / 200M triangles, are refused before
// anything is allocated.
#pragma once

#include <string>

#include "glimpse/cloud.h"
#include "glimpse/expected.h"

namespace glimpse {

// .off (OFF/COFF/NOFF headers; text after the face list is ignored), .obj (v and f records, any
// v/vt/vn index form, negative indices), .ply (ascii and binary of either endianness; vertex x,y,z of
// any scalar type, face vertex_indices or vertex_index lists), .stl (binary or ASCII, told apart by the
// binary size rule 84 + 50 n bytes; corners with identical coordinates welded into one vertex,
// triangles that collapse dropped). Polygons are fan-triangulated.
Expected<Mesh> read_mesh(const std::string& path);

// .pcd (ascii, binary, or binary_compressed as PCL's grabbers save frames; x y z anywhere among other
// fields, which are ignored: rgb, rgba, normals, ...; an organised WIDTH x HEIGHT frame gives one point
// per pixel in row order; NaN points, a depth camera's pixels without depth, are kept in every encoding:
// dropping them is the caller's choice), .ply, .xyz/.txt/.csv (x y z per line separated by blanks or
// commas, further columns ignored, '#' comments), .off/.obj/.stl (their vertices).
// Sensor: a PCD VIEWPOINT other than the default "0 0 0 1 0 0 0" sets Cloud.sensor to its translation
// (its rotation is ignored); files written by write_cloud also carry it as a "glimpse_sensor x y z"
// comment, which wins over VIEWPOINT and can say "at the origin"; without it a PCD with the default
// VIEWPOINT has no sensor (the format cannot tell the default from a sensor at the origin). A camera's
// frame (Cloud.frame) comes from a "glimpse_frame ax ay az ux uy uz fov_h fov_v" comment alike.
Expected<Cloud> read_cloud(const std::string& path);

// A depth camera's single view in a .pcd as PCL writes one: the camera at the VIEWPOINT's translation
// (the origin for the default VIEWPOINT: PCL's grabbers write frames in the camera's coordinates),
// looking along its rotation's +z with the image's up along its -y, and these full fields of view
// (degrees, in (0, 180)): Cloud.sensor and Cloud.frame. PCL's OpenNI grabbers write the VIEWPOINT
// "0 0 0 0 1 0 0" (a half turn about x, for their viewer) over points in the camera's own coordinates:
// it reads as the default. A file with glimpse_sensor and glimpse_frame comments keeps its own. Another
// format, or fields of view outside (0, 180): an error naming the file.
Expected<Cloud> read_camera_view(const std::string& path, float fov_h_deg, float fov_v_deg);

// .pcd (ascii, fields x y z), .ply (binary_little_endian, float x y z), .xyz (ascii "x y z" lines).
// Floats are printed with the shortest text that reads back bit-exactly.
Status write_cloud(const std::string& path, const Cloud& cloud);

}  // namespace glimpse
