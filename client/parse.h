// Small parsers shared by the commands: model references ("chair:3"), method lists ("bok,bog"), sensor
// positions, --up's axis or "floor". Method and status code names are the wire library's (proto/wire).
// Pure functions, no I/O.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "glimpse/cloud.h"
#include "glimpse/expected.h"
#include "client/inputs.h"
#include "glimpse/v1/glimpse.pb.h"

namespace glimpse::client {

// "NAME" or "NAME:VERSION" (VERSION a positive integer; NAME alone is version 0, the name's default).
// Names are 1-128 characters from [A-Za-z0-9._-], as in the proto.
// "latest" (version 0: unpinned, the newest) only where `allow_latest` (models set-default): elsewhere
// version 0 asks for the name's default, which may be pinned, and deleting it would delete every version.
Expected<v1::ModelRef> ParseModelRef(std::string_view text, bool allow_latest = false);
// "name:3", or just "name" for version 0.
std::string FormatModelRef(const v1::ModelRef& ref);

// Comma-separated names of wire::ParseMethod, e.g. "bok,bog"; blanks around names ignored; no duplicates;
// empty text -> empty list.
Expected<std::vector<v1::Method>> ParseMethodList(std::string_view text);

// A sensor position "X,Y,Z" in the cloud's frame (metres, finite), e.g. "0,0,0" for a camera-frame
// scan whose file does not say where the camera was.
Expected<Vec3> ParseSensor(std::string_view text);
// --track: "nearest", "X,Y,Z" (a point) or "X0,Y0,Z0,X1,Y1,Z1" (a box, min then max).
Expected<v1::TrackTarget> ParseTrackTarget(std::string_view text);

// A depth camera's full fields of view "HxV" in degrees, each in (0, 180), e.g. "57x43" (a Kinect).
Expected<FieldOfView> ParseFieldOfView(std::string_view text);

// --up's value: an axis as glimpse::parse_up reads it, or "floor" (the up of the floor a cloud file
// shows) where `allow_floor` (the single cloud files of classify and stream).
struct UpChoice {
  std::optional<Vec3> axis;
  bool floor = false;
};
Expected<UpChoice> ParseUpChoice(std::string_view text, bool allow_floor);

}  // namespace glimpse::client
