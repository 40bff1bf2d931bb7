// SPDX-License-Identifier: Apache-2.0
#include "panoptes/jsonl.h"

#include <algorithm>
#include <limits>
#include <stdexcept>
#include <utility>

#include <nlohmann/json.hpp>

#include "jsonl_fast.h"

namespace panoptes {

namespace {

// ordered_json keeps the keys in the documented order, which makes files readable and diffable.
using Json = nlohmann::ordered_json;

// Thrown only inside this file and turned into Parsed::error, so parsing never throws outward.
struct FieldError {
  std::string message;
};

std::string field_name(const std::string& prefix, const std::string& key) {
  return prefix.empty() ? key : prefix + "." + key;
}

std::string indexed(const std::string& name, std::size_t index) {
  return name + "[" + std::to_string(index) + "]";
}

std::string dump(const Json& json) {
  // Replacing invalid UTF-8 instead of throwing keeps a bad camera id from killing a recorder.
  return json.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

const Json* find_field(const Json& object, const std::string& key, const std::string& name, bool required) {
  const auto it = object.find(key);
  if (it == object.end() || it->is_null()) {
    if (required) throw FieldError{name + ": missing"};
    return nullptr;
  }
  return &*it;
}

// Stamps near 1.7e18 exceed double's 53-bit mantissa, so only JSON integers are accepted: a
// float would already have lost nanoseconds when it was written.
std::int64_t to_int64(const Json& value, const std::string& name) {
  if (value.is_number_unsigned()) {
    const auto unsigned_value = value.get<std::uint64_t>();
    if (unsigned_value > static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max())) {
      throw FieldError{name + ": integer out of range"};
    }
    return static_cast<std::int64_t>(unsigned_value);
  }
  if (value.is_number_integer()) return value.get<std::int64_t>();
  throw FieldError{name + ": expected an integer"};
}

double to_double(const Json& value, const std::string& name) {
  if (!value.is_number()) throw FieldError{name + ": expected a number"};
  return value.get<double>();
}

std::int64_t get_int64(const Json& object, const std::string& key, const std::string& prefix, bool required,
                       std::int64_t fallback = 0) {
  const std::string name = field_name(prefix, key);
  const Json* value = find_field(object, key, name, required);
  return value != nullptr ? to_int64(*value, name) : fallback;
}

int get_int(const Json& object, const std::string& key, const std::string& prefix, bool required) {
  const std::string name = field_name(prefix, key);
  const std::int64_t value = get_int64(object, key, prefix, required);
  if (value < std::numeric_limits<int>::min() || value > std::numeric_limits<int>::max()) {
    throw FieldError{name + ": integer out of range"};
  }
  return static_cast<int>(value);
}

double get_double(const Json& object, const std::string& key, const std::string& prefix, bool required) {
  const std::string name = field_name(prefix, key);
  const Json* value = find_field(object, key, name, required);
  return value != nullptr ? to_double(*value, name) : 0.0;
}

std::string get_string(const Json& object, const std::string& key, bool required) {
  const Json* value = find_field(object, key, key, required);
  if (value == nullptr) return {};
  if (!value->is_string()) throw FieldError{key + ": expected a string"};
  return value->get<std::string>();
}

template <std::size_t N, class Out>
bool get_numbers(const Json& object, const std::string& key, bool required, Out& out) {
  const Json* value = find_field(object, key, key, required);
  if (value == nullptr) return false;
  if (!value->is_array() || value->size() != N) {
    std::string reason = key + ": expected a list of " + std::to_string(N) + " numbers";
    if (value->is_array()) reason += ", got " + std::to_string(value->size());
    throw FieldError{reason};
  }
  for (std::size_t i = 0; i < N; ++i) out[i] = to_double((*value)[i], indexed(key, i));
  return true;
}

Json parse_object(std::string_view line) {
  Json json;
  try {
    json = Json::parse(line.begin(), line.end());
  } catch (const nlohmann::json::exception& error) {
    throw FieldError{std::string("not valid JSON: ") + error.what()};
  }
  if (!json.is_object()) throw FieldError{"expected a JSON object"};
  return json;
}

template <class T, class Parse>
Parsed<T> parse_record(std::string_view line, Parse&& parse) {
  Parsed<T> result;
  try {
    result.value = parse(parse_object(line));
  } catch (const FieldError& error) {
    result.error = error.message;
  } catch (const std::exception& error) {
    // Belt and braces: a library surprise must still come back as a message, never escape.
    result.error = error.what();
  }
  return result;
}

std::optional<TrackStatus> status_from_string(std::string_view text) {
  if (text == "tentative") return TrackStatus::kTentative;
  if (text == "confirmed") return TrackStatus::kConfirmed;
  if (text == "coasting") return TrackStatus::kCoasting;
  return std::nullopt;
}

template <class T, class ParseLine>
std::vector<T> read_records(const std::filesystem::path& path, std::vector<std::string>* errors,
                            ParseLine&& parse_line) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path.string() + ": cannot open");
  std::vector<T> records;
  std::string line;
  std::size_t line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.find_first_not_of(" \t") == std::string::npos) continue;
    Parsed<T> parsed = parse_line(line);
    if (parsed.value) {
      records.push_back(std::move(*parsed.value));
    } else if (errors != nullptr) {
      errors->push_back(path.string() + ":" + std::to_string(line_number) + ": " + parsed.error);
    }
  }
  return records;
}

}  // namespace

namespace {

// True if `text` goes into a JSON string as it is (no escape needed, ASCII): what the fast paths
// write and read; anything else goes through the JSON library.
bool plain_text(std::string_view text) {
  return std::all_of(text.begin(), text.end(), jsonl_fast::plain_char);
}

std::string feature_frame_line_full(const FeatureFrame& frame) {
  Json blobs = Json::array();
  for (const Blob& blob : frame.blobs) {
    blobs.push_back({{"x", blob.x},
                     {"y", blob.y},
                     {"area", blob.area},
                     {"sum", blob.sum},
                     {"peak", blob.peak},
                     {"m20", blob.m20},
                     {"m11", blob.m11},
                     {"m02", blob.m02},
                     {"bbox", {blob.x0, blob.y0, blob.x1, blob.y1}}});
  }
  Json json = {{"camera_id", frame.camera_id},
               {"frame", frame.frame},
               {"stamp_ns", frame.stamp_ns},
               {"arrival_ns", frame.arrival_ns},
               {"processing_ns", frame.processing_ns}};
  // Optional, so files without delivery timing stay exactly as they were.
  if (frame.received_ns != 0) json["received_ns"] = frame.received_ns;
  json["blobs"] = std::move(blobs);
  return dump(json);
}

}  // namespace

// The same keys in the same order as the full writer; a camera id that needs escaping goes
// through the JSON library.
std::string to_json_line(const FeatureFrame& frame) {
  if (!plain_text(frame.camera_id)) return feature_frame_line_full(frame);
  using jsonl_fast::append_field;
  using jsonl_fast::append_number;
  std::string line;
  line.reserve(96 + 160 * frame.blobs.size());
  line += "{\"camera_id\":\"";
  line += frame.camera_id;
  line += "\",\"frame\":";
  append_number(line, std::int64_t{frame.frame});
  append_field(line, ",\"stamp_ns\":", std::int64_t{frame.stamp_ns});
  append_field(line, ",\"arrival_ns\":", std::int64_t{frame.arrival_ns});
  append_field(line, ",\"processing_ns\":", std::int64_t{frame.processing_ns});
  if (frame.received_ns != 0) {
    append_field(line, ",\"received_ns\":", std::int64_t{frame.received_ns});
  }
  line += ",\"blobs\":[";
  for (std::size_t i = 0; i < frame.blobs.size(); ++i) {
    const Blob& blob = frame.blobs[i];
    line += i == 0 ? "{\"x\":" : ",{\"x\":";
    append_number(line, blob.x);
    append_field(line, ",\"y\":", blob.y);
    append_field(line, ",\"area\":", blob.area);
    append_field(line, ",\"sum\":", blob.sum);
    append_field(line, ",\"peak\":", std::int64_t{blob.peak});
    append_field(line, ",\"m20\":", blob.m20);
    append_field(line, ",\"m11\":", blob.m11);
    append_field(line, ",\"m02\":", blob.m02);
    const std::int64_t box[4] = {blob.x0, blob.y0, blob.x1, blob.y1};
    jsonl_fast::append_list(line, ",\"bbox\":", box, 4);
    line += '}';
  }
  line += "]}";
  return line;
}

// Written without a JSON document (jsonl_fast.h): the estimator writes one line per track and
// camera frame, and readers (panoptes_eval, the grid) read hundreds of thousands of them.
std::string to_json_line(const TrackRecord& track) {
  using jsonl_fast::append_field;
  using jsonl_fast::append_number;
  std::string line;
  line.reserve(320);
  line += "{\"stamp_ns\":";
  append_number(line, std::int64_t{track.stamp_ns});
  append_field(line, ",\"id\":", std::int64_t{track.id});
  jsonl_fast::append_list(line, ",\"p\":", track.p.data(), 3);
  jsonl_fast::append_list(line, ",\"v\":", track.v.data(), 3);
  jsonl_fast::append_list(line, ",\"cov\":", track.position_covariance.data(), 6);
  line += ",\"status\":\"";
  line += to_string(track.status);
  line += "\",\"cameras\":";
  append_number(line, std::int64_t{track.cameras});
  line += '}';
  return line;
}

std::string to_json_line(const PoseRecord& pose) {
  Json json = {{"stamp_ns", pose.stamp_ns},
               {"body", pose.body},
               {"p", {pose.p.x(), pose.p.y(), pose.p.z()}},
               {"q", {pose.q.x(), pose.q.y(), pose.q.z(), pose.q.w()}},
               {"v", {pose.v.x(), pose.v.y(), pose.v.z()}},
               {"w", {pose.w.x(), pose.w.y(), pose.w.z()}},
               {"horizon_ns", pose.horizon_ns},
               {"quality", pose.quality},
               {"cameras", pose.cameras},
               {"sigma", pose.sigma}};
  return dump(json);
}

namespace {

bool parse_blob_fast(jsonl_fast::Cursor& in, Blob& blob) {
  int box[4] = {0, 0, 0, 0};
  const bool read =
      in.literal("{\"x\":") && in.number(blob.x) && in.literal(",\"y\":") && in.number(blob.y) &&
      in.literal(",\"area\":") && in.number(blob.area) && in.literal(",\"sum\":") && in.number(blob.sum) &&
      in.literal(",\"peak\":") && in.integer(blob.peak) && in.literal(",\"m20\":") && in.number(blob.m20) &&
      in.literal(",\"m11\":") && in.number(blob.m11) && in.literal(",\"m02\":") && in.number(blob.m02) &&
      in.literal(",\"bbox\":[") && in.integer(box[0]) && in.literal(",") && in.integer(box[1]) &&
      in.literal(",") && in.integer(box[2]) && in.literal(",") && in.integer(box[3]) && in.literal("]}");
  blob.x0 = box[0];
  blob.y0 = box[1];
  blob.x1 = box[2];
  blob.y1 = box[3];
  return read;
}

// A line exactly as to_json_line writes it, or nothing (the full parser then reads it).
std::optional<FeatureFrame> parse_feature_frame_fast(std::string_view line) {
  jsonl_fast::Cursor in(line);
  FeatureFrame frame;
  std::string_view camera_id;
  if (!(in.literal("{\"camera_id\":") && in.plain_string(camera_id) && in.literal(",\"frame\":") &&
        in.integer(frame.frame) && in.literal(",\"stamp_ns\":") && in.integer(frame.stamp_ns) &&
        in.literal(",\"arrival_ns\":") && in.integer(frame.arrival_ns) && in.literal(",\"processing_ns\":") &&
        in.integer(frame.processing_ns))) {
    return std::nullopt;
  }
  if (in.literal(",\"received_ns\":") && !in.integer(frame.received_ns)) return std::nullopt;
  if (!in.literal(",\"blobs\":[")) return std::nullopt;
  while (!in.peek(']')) {
    if (!frame.blobs.empty() && !in.literal(",")) return std::nullopt;
    if (!parse_blob_fast(in, frame.blobs.emplace_back())) return std::nullopt;
  }
  if (!(in.literal("]}") && in.at_end())) return std::nullopt;
  frame.camera_id = camera_id;
  return frame;
}

}  // namespace

Parsed<FeatureFrame> parse_feature_frame(std::string_view line) {
  if (auto frame = parse_feature_frame_fast(line)) {
    Parsed<FeatureFrame> result;
    result.value = std::move(*frame);
    return result;
  }
  return parse_record<FeatureFrame>(line, [](const Json& json) {
    FeatureFrame frame;
    frame.camera_id = get_string(json, "camera_id", true);
    frame.frame = get_int64(json, "frame", "", true);
    frame.stamp_ns = get_int64(json, "stamp_ns", "", true);
    frame.arrival_ns = get_int64(json, "arrival_ns", "", false);
    frame.processing_ns = get_int64(json, "processing_ns", "", false);
    frame.received_ns = get_int64(json, "received_ns", "", false);
    const Json* blobs = find_field(json, "blobs", "blobs", true);
    if (!blobs->is_array()) throw FieldError{"blobs: expected a list"};
    frame.blobs.reserve(blobs->size());
    for (std::size_t i = 0; i < blobs->size(); ++i) {
      const std::string prefix = indexed("blobs", i);
      const Json& item = (*blobs)[i];
      if (!item.is_object()) throw FieldError{prefix + ": expected an object"};
      Blob blob;
      blob.x = get_double(item, "x", prefix, true);
      blob.y = get_double(item, "y", prefix, true);
      blob.area = get_double(item, "area", prefix, false);
      blob.sum = get_double(item, "sum", prefix, false);
      blob.peak = get_int(item, "peak", prefix, false);
      blob.m20 = get_double(item, "m20", prefix, false);
      blob.m11 = get_double(item, "m11", prefix, false);
      blob.m02 = get_double(item, "m02", prefix, false);
      if (const Json* bbox = find_field(item, "bbox", prefix + ".bbox", false)) {
        if (!bbox->is_array() || bbox->size() != 4 ||
            !std::all_of(bbox->begin(), bbox->end(), [](const Json& v) { return v.is_number_integer(); })) {
          throw FieldError{prefix + ".bbox: expected [x0, y0, x1, y1] in whole pixels"};
        }
        blob.x0 = (*bbox)[0].get<int>();
        blob.y0 = (*bbox)[1].get<int>();
        blob.x1 = (*bbox)[2].get<int>();
        blob.y1 = (*bbox)[3].get<int>();
      }
      frame.blobs.push_back(blob);
    }
    return frame;
  });
}

namespace {

// A line exactly as to_json_line writes it, or nothing (the full parser then reads it).
std::optional<TrackRecord> parse_track_fast(std::string_view line) {
  jsonl_fast::Cursor in(line);
  TrackRecord track;
  std::string_view status;
  const bool read = in.literal("{\"stamp_ns\":") && in.integer(track.stamp_ns) && in.literal(",\"id\":") &&
                    in.integer(track.id) && in.literal(",\"p\":") && in.numbers(track.p, 3) &&
                    in.literal(",\"v\":") && in.numbers(track.v, 3) && in.literal(",\"cov\":") &&
                    in.numbers(track.position_covariance, 6) && in.literal(",\"status\":") &&
                    in.plain_string(status) && in.literal(",\"cameras\":") && in.integer(track.cameras) &&
                    in.literal("}") && in.at_end();
  const auto known = read ? status_from_string(status) : std::nullopt;
  if (!known) return std::nullopt;
  track.status = *known;
  return track;
}

}  // namespace

Parsed<TrackRecord> parse_track(std::string_view line) {
  if (auto track = parse_track_fast(line)) {
    Parsed<TrackRecord> result;
    result.value = std::move(*track);
    return result;
  }
  return parse_record<TrackRecord>(line, [](const Json& json) {
    TrackRecord track;
    track.stamp_ns = get_int64(json, "stamp_ns", "", true);
    track.id = get_int64(json, "id", "", true);
    get_numbers<3>(json, "p", true, track.p);
    get_numbers<3>(json, "v", true, track.v);
    get_numbers<6>(json, "cov", false, track.position_covariance);
    if (find_field(json, "status", "status", false) != nullptr) {
      const auto status = status_from_string(get_string(json, "status", true));
      if (!status) throw FieldError{"status: expected tentative, confirmed or coasting"};
      track.status = *status;
    }
    track.cameras = get_int(json, "cameras", "", false);
    return track;
  });
}

Parsed<PoseRecord> parse_pose(std::string_view line) {
  return parse_record<PoseRecord>(line, [](const Json& json) {
    PoseRecord pose;
    pose.stamp_ns = get_int64(json, "stamp_ns", "", true);
    pose.body = get_string(json, "body", true);
    get_numbers<3>(json, "p", true, pose.p);
    get_numbers<4>(json, "q", true, pose.q);
    get_numbers<3>(json, "v", false, pose.v);
    get_numbers<3>(json, "w", false, pose.w);
    pose.horizon_ns = get_int64(json, "horizon_ns", "", false);
    return pose;
  });
}

std::vector<FeatureFrame> read_feature_frames(const std::filesystem::path& path,
                                              std::vector<std::string>* errors) {
  return read_records<FeatureFrame>(path, errors, parse_feature_frame);
}

std::vector<TrackRecord> read_tracks(const std::filesystem::path& path, std::vector<std::string>* errors) {
  return read_records<TrackRecord>(path, errors, parse_track);
}

std::vector<PoseRecord> read_poses(const std::filesystem::path& path, std::vector<std::string>* errors) {
  return read_records<PoseRecord>(path, errors, parse_pose);
}

JsonlWriter::JsonlWriter(const std::filesystem::path& path)
    : path_(path), out_(path, std::ios::out | std::ios::trunc) {
  if (!out_) throw std::runtime_error(path_.string() + ": cannot open for writing");
}

void JsonlWriter::write_line(const std::string& line) {
  out_ << line << '\n';
  if (!out_) throw std::runtime_error(path_.string() + ": write failed");
}

void JsonlWriter::flush() {
  out_.flush();
  if (!out_) throw std::runtime_error(path_.string() + ": write failed");
}

}  // namespace panoptes
