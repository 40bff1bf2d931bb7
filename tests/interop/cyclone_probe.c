// SPDX-License-Identifier: Apache-2.0
// panoptes_cyclone_probe: an application built on Eclipse Cyclone DDS (its C API, types generated
// by Cyclone's own idlc from idl/panoptes.idl and idl/ros2.idl) that reads what estimator_node
// publishes with Fast DDS, as evidence that any DDS implementation and ROS 2 can consume it
// (issue 15, docs/interop.md). It subscribes to the native rt/panoptes/bodies and rt/panoptes/tracks
// (plus rt/panoptes/frames and the transient-local rt/panoptes/body_descriptions) and, with --ros2, to the
// ROS 2 topics rt/panoptes/<body>/pose, rt/panoptes/<body>/twist, rt/tf, rt/rigid_bodies and rt/markers;
// writes what it decoded as Pose and Track JSON Lines (docs/contracts.md) for panoptes_eval; cross-checks the
// ROS 2 topics against each other and the native ones; and prints a JSON summary. Exit 0: every topic read
// had samples and every check held; 1: not; 2: bad arguments or no DDS.
#include <errno.h>
#include <inttypes.h>
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <dds/dds.h>

#include "panoptes.h"
#include "ros2.h"

#ifndef PANOPTES_CYCLONE_CONFIG
#define PANOPTES_CYCLONE_CONFIG ""
#endif

enum {
  kMaxBodies = 16,
  kMaxNameLength = 63,
  kTakeBatch = 64,
  kReaderDepth = 256,  // samples a reader keeps (per instance) between two takes
  kMaxReaders = 16 + 3 * kMaxBodies,
};

// Two values are "the same" when they differ by less than this: the ROS 2 messages are built from
// the same doubles as the native ones, so anything beyond rounding is a conversion error.
static const double kSameValue = 1e-9;

typedef struct Options {
  uint32_t domain;
  double duration_s;
  char bodies[kMaxBodies][kMaxNameLength + 1];
  int body_count;
  bool ros2;
  const char* out_dir;
  const char* config;
  const char* world_frame;
} Options;

// Growable arrays of decoded records (the checks run after the capture, so that the order in which
// topics arrive does not matter).
typedef struct PoseRecord {
  int body;
  int64_t stamp_ns;
  int64_t horizon_ns;
  // The time the pose is for: stamp_ns + horizon_ns (the ROS 2 header stamp of a predicted pose).
  // Records of different topics are paired on (body, pose_time_ns).
  int64_t pose_time_ns;
  double p[3];
  double q[4];  // x, y, z, w
  double v[3];
  double w[3];
  float quality;
} PoseRecord;

typedef struct PoseList {
  PoseRecord* items;
  size_t count;
  size_t capacity;
} PoseList;

typedef struct FrameNumbers {
  uint64_t count;
  uint64_t not_increasing;  // frame_number <= the previous one
  uint64_t last;
} FrameNumbers;

typedef struct MarkerStats {
  uint64_t markers;
  uint64_t labelled;   // named "<body>/<index>" with a known body
  uint64_t bad_names;  // neither "" nor "<body>/<index>"
  uint64_t not_finite;
  uint64_t with_track;                  // translation equals a track of the TrackFrame with the same stamp
  uint64_t frames_with_track_frame;     // a TrackFrame with the same stamp was decoded
  uint64_t in_frames_with_track_frame;  // markers of those messages
} MarkerStats;

// Positions of every track of every decoded TrackFrame (or marker of every rt/markers message), for
// the rt/markers check.
typedef struct FrameSlice {
  int64_t stamp_ns;
  size_t first;  // index into TrackFrameIndex.positions
  size_t count;
} FrameSlice;

typedef struct TrackFrameIndex {
  FrameSlice* frames;
  size_t frame_count;
  size_t frame_capacity;
  double (*positions)[3];
  size_t positions_count;
  size_t positions_capacity;
} TrackFrameIndex;

typedef struct Capture {
  const Options* options;
  FILE* native_poses_out;
  FILE* native_tracks_out;
  FILE* ros_poses_out;
  uint64_t native_poses;
  uint64_t native_poses_reliable;
  FrameNumbers mocap_frames;  // rt/panoptes/frames
  uint64_t mocap_frame_bodies_unknown;
  uint64_t mocap_frame_markers;
  uint64_t mocap_frame_markers_labelled;
  uint64_t body_descriptions;  // rt/panoptes/body_descriptions samples
  uint64_t body_descriptions_wrong;
  uint64_t body_descriptions_generation;
  uint64_t native_poses_unknown_body;
  uint64_t native_pose_not_finite;
  uint64_t track_frames;
  uint64_t tracks;
  uint64_t track_not_finite;
  uint64_t ros_pose_reliable[kMaxBodies];
  uint64_t ros_pose_best_effort[kMaxBodies];
  uint64_t ros_pose_bad_frame;
  uint64_t twists;
  uint64_t twist_bad_frame;
  uint64_t tf_messages;
  uint64_t tf_transforms;
  uint64_t tf_bad_parent;
  uint64_t tf_unknown_child;
  uint64_t rigid_body_messages;
  uint64_t rigid_bodies_unknown_name;
  uint64_t markers_messages;
  FrameNumbers rigid_body_frames;
  FrameNumbers marker_frames;
  MarkerStats marker_stats;
  PoseList native;               // rt/panoptes/bodies
  PoseList mocap_bodies;         // rt/panoptes/frames: the tracked bodies' poses
  PoseList ros_poses;            // rt/panoptes/<body>/pose (best-effort reader)
  PoseList ros_twists;           // rt/panoptes/<body>/twist: v, w
  PoseList tf;                   // rt/tf transforms
  PoseList rigid_bodies;         // rt/rigid_bodies poses
  TrackFrameIndex track_index;   // rt/panoptes/tracks positions
  TrackFrameIndex marker_index;  // rt/markers translations
} Capture;

// ------------------------------------------------------------------------------------------------
// Small helpers.

static void* grow(void* items, size_t* capacity, size_t needed, size_t item_size) {
  if (needed <= *capacity) return items;
  size_t next = *capacity == 0 ? 1024 : *capacity * 2;
  while (next < needed) next *= 2;
  void* grown = realloc(items, next * item_size);
  if (grown == NULL) {
    fprintf(stderr, "panoptes_cyclone_probe: out of memory\n");
    abort();  // an invariant of a test tool: a capture of a few minutes fits in memory
  }
  *capacity = next;
  return grown;
}

static PoseRecord* pose_list_add(PoseList* list) {
  list->items = grow(list->items, &list->capacity, list->count + 1, sizeof(PoseRecord));
  PoseRecord* record = &list->items[list->count++];
  memset(record, 0, sizeof *record);
  return record;
}

static int body_index(const Options* options, const char* name) {
  for (int i = 0; i < options->body_count; ++i) {
    if (strcmp(options->bodies[i], name) == 0) return i;
  }
  return -1;
}

static bool all_finite(const double* values, int count) {
  for (int i = 0; i < count; ++i) {
    if (!isfinite(values[i])) return false;
  }
  return true;
}

static int64_t ros_stamp_ns(const builtin_interfaces_msg_dds__Time_* stamp) {
  return (int64_t)stamp->sec * 1000000000LL + (int64_t)stamp->nanosec;
}

static void write_doubles(FILE* out, const double* values, int count) {
  fputc('[', out);
  for (int i = 0; i < count; ++i) fprintf(out, i == 0 ? "%.17g" : ",%.17g", values[i]);
  fputc(']', out);
}

// A Pose JSON Lines record (docs/contracts.md, "Pose JSON Lines").
static void write_pose_line(FILE* out, const Options* options, const PoseRecord* pose) {
  if (out == NULL) return;
  fprintf(out, "{\"stamp_ns\":%" PRId64 ",\"body\":\"%s\",\"p\":", pose->stamp_ns,
          options->bodies[pose->body]);
  write_doubles(out, pose->p, 3);
  fputs(",\"q\":", out);
  write_doubles(out, pose->q, 4);
  fputs(",\"v\":", out);
  write_doubles(out, pose->v, 3);
  fputs(",\"w\":", out);
  write_doubles(out, pose->w, 3);
  fprintf(out, ",\"horizon_ns\":%" PRId64 ",\"quality\":%.9g}\n", pose->horizon_ns, (double)pose->quality);
}

static const char* track_status_name(uint8_t status) {
  switch (status) {
    case 0:
      return "tentative";
    case 1:
      return "confirmed";
    case 2:
      return "coasting";
    default:
      return NULL;
  }
}

// ------------------------------------------------------------------------------------------------
// Decoding, one function per topic.

static void on_native_pose(Capture* capture, const panoptes_msg_BodyPose* sample) {
  const int body = body_index(capture->options, sample->name);
  if (body < 0) {
    ++capture->native_poses_unknown_body;
    return;
  }
  PoseRecord* pose = pose_list_add(&capture->native);
  pose->body = body;
  pose->stamp_ns = sample->stamp_ns;
  pose->horizon_ns = sample->prediction_horizon_ns;
  pose->pose_time_ns = sample->stamp_ns + sample->prediction_horizon_ns;
  memcpy(pose->p, sample->pose.position, sizeof pose->p);
  memcpy(pose->q, sample->pose.orientation, sizeof pose->q);
  memcpy(pose->v, sample->linear_velocity, sizeof pose->v);
  memcpy(pose->w, sample->angular_velocity, sizeof pose->w);
  pose->quality = sample->quality;
  ++capture->native_poses;
  if (!all_finite(pose->p, 3) || !all_finite(pose->q, 4)) ++capture->native_pose_not_finite;
  write_pose_line(capture->native_poses_out, capture->options, pose);
}

static void index_track(TrackFrameIndex* index, const double position[3]) {
  index->positions = grow((void*)index->positions, &index->positions_capacity, index->positions_count + 1,
                          sizeof *index->positions);
  memcpy(index->positions[index->positions_count++], position, sizeof(double[3]));
}

static void index_track_frame(TrackFrameIndex* index, int64_t stamp_ns, size_t first, size_t count) {
  index->frames = grow(index->frames, &index->frame_capacity, index->frame_count + 1, sizeof *index->frames);
  const FrameSlice slice = {stamp_ns, first, count};
  index->frames[index->frame_count++] = slice;
}

static void on_track_frame(Capture* capture, const panoptes_msg_TrackFrame* sample) {
  ++capture->track_frames;
  const size_t first = capture->track_index.positions_count;
  for (uint32_t i = 0; i < sample->tracks._length; ++i) {
    const panoptes_msg_Track* track = &sample->tracks._buffer[i];
    const char* status = track_status_name(track->status);
    if (status == NULL || !all_finite(track->position, 3) || !all_finite(track->velocity, 3)) {
      ++capture->track_not_finite;
      continue;
    }
    ++capture->tracks;
    index_track(&capture->track_index, track->position);
    FILE* out = capture->native_tracks_out;
    if (out == NULL) continue;
    // A Track JSON Lines record (docs/contracts.md, "Track JSON Lines").
    fprintf(out, "{\"stamp_ns\":%" PRId64 ",\"id\":%" PRId64 ",\"p\":", sample->stamp_ns, track->id);
    write_doubles(out, track->position, 3);
    fputs(",\"v\":", out);
    write_doubles(out, track->velocity, 3);
    fputs(",\"cov\":", out);
    write_doubles(out, track->covariance, 6);
    fprintf(out, ",\"status\":\"%s\",\"cameras\":%u}\n", status, (unsigned)track->cameras);
  }
  index_track_frame(&capture->track_index, sample->stamp_ns, first,
                    capture->track_index.positions_count - first);
}

static void count_frame_number(FrameNumbers* numbers, uint64_t frame_number) {
  if (numbers->count > 0 && frame_number <= numbers->last) ++numbers->not_increasing;
  numbers->last = frame_number;
  ++numbers->count;
}

static void on_mocap_frame(Capture* capture, const panoptes_msg_MocapFrame* sample) {
  count_frame_number(&capture->mocap_frames, sample->frame_number);
  for (uint32_t i = 0; i < sample->bodies._length; ++i) {
    const panoptes_msg_FrameBody* frame_body = &sample->bodies._buffer[i];
    const int body = body_index(capture->options, frame_body->name);
    if (body < 0) {
      ++capture->mocap_frame_bodies_unknown;
      continue;
    }
    if (!frame_body->tracking_valid) continue;
    PoseRecord* pose = pose_list_add(&capture->mocap_bodies);
    pose->body = body;
    pose->stamp_ns = sample->stamp_ns;
    pose->pose_time_ns = sample->stamp_ns + frame_body->prediction_horizon_ns;
    memcpy(pose->p, frame_body->pose.position, sizeof pose->p);
    memcpy(pose->q, frame_body->pose.orientation, sizeof pose->q);
  }
  capture->mocap_frame_markers += sample->markers._length;
  for (uint32_t i = 0; i < sample->markers._length; ++i) {
    if (sample->markers._buffer[i].body[0] != '\0') ++capture->mocap_frame_markers_labelled;
  }
}

// The whole set of defined bodies: exactly the names given with --bodies, each with a layout.
static void on_body_descriptions(Capture* capture, const panoptes_msg_BodyDescriptions* sample) {
  ++capture->body_descriptions;
  capture->body_descriptions_generation = sample->generation;
  bool seen[kMaxBodies] = {false};
  bool right = (int)sample->bodies._length == capture->options->body_count;
  for (uint32_t i = 0; right && i < sample->bodies._length; ++i) {
    const int body = body_index(capture->options, sample->bodies._buffer[i].name);
    right = body >= 0 && !seen[body] && sample->bodies._buffer[i].markers._length >= 3;
    if (body >= 0) seen[body] = true;
  }
  if (!right) ++capture->body_descriptions_wrong;
}

static void on_ros_pose(Capture* capture, int body, bool reliable,
                        const geometry_msgs_msg_dds__PoseStamped_* sample) {
  if (reliable) {
    ++capture->ros_pose_reliable[body];
    return;
  }
  ++capture->ros_pose_best_effort[body];
  if (strcmp(sample->header.frame_id, capture->options->world_frame) != 0) ++capture->ros_pose_bad_frame;
  PoseRecord* pose = pose_list_add(&capture->ros_poses);
  pose->body = body;
  pose->stamp_ns = ros_stamp_ns(&sample->header.stamp);
  pose->pose_time_ns = pose->stamp_ns;
  const geometry_msgs_msg_dds__Pose_* source = &sample->pose;
  const double p[3] = {source->position.x, source->position.y, source->position.z};
  const double q[4] = {source->orientation.x, source->orientation.y, source->orientation.z,
                       source->orientation.w};
  memcpy(pose->p, p, sizeof p);
  memcpy(pose->q, q, sizeof q);
  write_pose_line(capture->ros_poses_out, capture->options, pose);
}

static void on_ros_twist(Capture* capture, int body, const geometry_msgs_msg_dds__TwistStamped_* sample) {
  ++capture->twists;
  if (strcmp(sample->header.frame_id, capture->options->world_frame) != 0) ++capture->twist_bad_frame;
  PoseRecord* twist = pose_list_add(&capture->ros_twists);
  twist->body = body;
  twist->stamp_ns = ros_stamp_ns(&sample->header.stamp);
  twist->pose_time_ns = twist->stamp_ns;
  const geometry_msgs_msg_dds__Twist_* source = &sample->twist;
  const double v[3] = {source->linear.x, source->linear.y, source->linear.z};
  const double w[3] = {source->angular.x, source->angular.y, source->angular.z};
  memcpy(twist->v, v, sizeof v);
  memcpy(twist->w, w, sizeof w);
}

static void on_tf(Capture* capture, const tf2_msgs_msg_dds__TFMessage_* sample) {
  ++capture->tf_messages;
  for (uint32_t i = 0; i < sample->transforms._length; ++i) {
    const geometry_msgs_msg_dds__TransformStamped_* transform = &sample->transforms._buffer[i];
    ++capture->tf_transforms;
    if (strcmp(transform->header.frame_id, capture->options->world_frame) != 0) ++capture->tf_bad_parent;
    const int body = body_index(capture->options, transform->child_frame_id);
    if (body < 0) {
      ++capture->tf_unknown_child;
      continue;
    }
    PoseRecord* pose = pose_list_add(&capture->tf);
    pose->body = body;
    pose->stamp_ns = ros_stamp_ns(&transform->header.stamp);
    pose->pose_time_ns = pose->stamp_ns;
    const geometry_msgs_msg_dds__Transform_* source = &transform->transform;
    const double p[3] = {source->translation.x, source->translation.y, source->translation.z};
    const double q[4] = {source->rotation.x, source->rotation.y, source->rotation.z, source->rotation.w};
    memcpy(pose->p, p, sizeof p);
    memcpy(pose->q, q, sizeof q);
  }
}

static void on_rigid_bodies(Capture* capture, const mocap4r2_msgs_msg_dds__RigidBodies_* sample) {
  ++capture->rigid_body_messages;
  count_frame_number(&capture->rigid_body_frames, sample->frame_number);
  for (uint32_t i = 0; i < sample->rigidbodies._length; ++i) {
    const mocap4r2_msgs_msg_dds__RigidBody_* rigid_body = &sample->rigidbodies._buffer[i];
    const int body = body_index(capture->options, rigid_body->rigid_body_name);
    if (body < 0) {
      ++capture->rigid_bodies_unknown_name;
      continue;
    }
    PoseRecord* pose = pose_list_add(&capture->rigid_bodies);
    pose->body = body;
    pose->stamp_ns = ros_stamp_ns(&sample->header.stamp);
    pose->pose_time_ns = pose->stamp_ns;
    const geometry_msgs_msg_dds__Pose_* source = &rigid_body->pose;
    const double p[3] = {source->position.x, source->position.y, source->position.z};
    const double q[4] = {source->orientation.x, source->orientation.y, source->orientation.z,
                         source->orientation.w};
    memcpy(pose->p, p, sizeof p);
    memcpy(pose->q, q, sizeof q);
  }
}

// "" (unlabelled) or "<body>/<index>" with a defined body and a non-negative index.
static bool marker_name_ok(const Options* options, const char* name, bool* labelled) {
  *labelled = false;
  if (name[0] == '\0') return true;
  const char* slash = strrchr(name, '/');
  if (slash == NULL || slash == name || slash[1] == '\0') return false;
  char body[kMaxNameLength + 1];
  const size_t length = (size_t)(slash - name);
  if (length > kMaxNameLength) return false;
  memcpy(body, name, length);
  body[length] = '\0';
  char* end = NULL;
  errno = 0;
  const long index = strtol(slash + 1, &end, 10);
  if (errno != 0 || *end != '\0' || index < 0 || body_index(options, body) < 0) return false;
  *labelled = true;
  return true;
}

static void on_markers(Capture* capture, const mocap4r2_msgs_msg_dds__Markers_* sample) {
  ++capture->markers_messages;
  count_frame_number(&capture->marker_frames, sample->frame_number);
  MarkerStats* stats = &capture->marker_stats;
  const size_t first = capture->marker_index.positions_count;
  for (uint32_t i = 0; i < sample->markers._length; ++i) {
    const mocap4r2_msgs_msg_dds__Marker_* marker = &sample->markers._buffer[i];
    ++stats->markers;
    bool labelled = false;
    if (!marker_name_ok(capture->options, marker->marker_name, &labelled)) ++stats->bad_names;
    if (labelled) ++stats->labelled;
    const double p[3] = {marker->translation.x, marker->translation.y, marker->translation.z};
    if (!all_finite(p, 3)) ++stats->not_finite;
    index_track(&capture->marker_index, p);
  }
  index_track_frame(&capture->marker_index, ros_stamp_ns(&sample->header.stamp), first,
                    capture->marker_index.positions_count - first);
}

// ------------------------------------------------------------------------------------------------
// Readers.

typedef enum TopicKind {
  kNativePose,
  kNativePoseReliable,
  kNativeTracks,
  kNativeFrames,
  kNativeBodyDescriptions,
  kRosPose,
  kRosPoseReliable,
  kRosTwist,
  kRosTf,
  kRosRigidBodies,
  kRosMarkers,
} TopicKind;

typedef struct Reader {
  dds_entity_t entity;
  TopicKind kind;
  int body;  // per-body topics
  char topic_name[128];
} Reader;

typedef struct Readers {
  Reader items[kMaxReaders];
  int count;
} Readers;

typedef enum ReaderQos { kBestEffort, kReliable, kReliableTransientLocal } ReaderQos;

static bool add_reader(dds_entity_t participant, Readers* readers, TopicKind kind, int body,
                       const dds_topic_descriptor_t* descriptor, const char* topic_name,
                       ReaderQos reader_qos) {
  Reader* reader = &readers->items[readers->count];
  snprintf(reader->topic_name, sizeof reader->topic_name, "%s", topic_name);
  reader->kind = kind;
  reader->body = body;
  const dds_entity_t topic = dds_create_topic(participant, descriptor, topic_name, NULL, NULL);
  if (topic < 0) {
    fprintf(stderr, "panoptes_cyclone_probe: topic %s: %s\n", topic_name, dds_strretcode(topic));
    return false;
  }
  dds_qos_t* qos = dds_create_qos();
  dds_qset_reliability(
      qos, reader_qos == kBestEffort ? DDS_RELIABILITY_BEST_EFFORT : DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
  // The body descriptions are kept for late joiners (transient-local, keep-last 1).
  if (reader_qos == kReliableTransientLocal) dds_qset_durability(qos, DDS_DURABILITY_TRANSIENT_LOCAL);
  dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, reader_qos == kReliableTransientLocal ? 1 : kReaderDepth);
  reader->entity = dds_create_reader(participant, topic, qos, NULL);
  dds_delete_qos(qos);
  if (reader->entity < 0) {
    fprintf(stderr, "panoptes_cyclone_probe: reader of %s: %s\n", topic_name, dds_strretcode(reader->entity));
    return false;
  }
  ++readers->count;
  return true;
}

static bool create_native_readers(dds_entity_t participant, Readers* readers) {
  // rt/panoptes/bodies twice: best effort (what the topic asks) and reliable (what its writers offer).
  return add_reader(participant, readers, kNativePose, -1, &panoptes_msg_BodyPose_desc, "rt/panoptes/bodies",
                    kBestEffort) &&
         add_reader(participant, readers, kNativePoseReliable, -1, &panoptes_msg_BodyPose_desc,
                    "rt/panoptes/bodies", kReliable) &&
         add_reader(participant, readers, kNativeTracks, -1, &panoptes_msg_TrackFrame_desc,
                    "rt/panoptes/tracks", kBestEffort) &&
         add_reader(participant, readers, kNativeFrames, -1, &panoptes_msg_MocapFrame_desc,
                    "rt/panoptes/frames", kBestEffort) &&
         add_reader(participant, readers, kNativeBodyDescriptions, -1, &panoptes_msg_BodyDescriptions_desc,
                    "rt/panoptes/body_descriptions", kReliableTransientLocal);
}

static bool create_readers(dds_entity_t participant, const Options* options, Readers* readers) {
  bool ok = create_native_readers(participant, readers);
  if (!options->ros2) return ok;
  for (int body = 0; ok && body < options->body_count; ++body) {
    const dds_topic_descriptor_t* pose = &geometry_msgs_msg_dds__PoseStamped__desc;
    char name[128];
    snprintf(name, sizeof name, "rt/panoptes/%s/pose", options->bodies[body]);
    // Both QoS a ROS 2 subscriber asks for: SensorDataQoS (best effort) and the default (reliable).
    ok = add_reader(participant, readers, kRosPose, body, pose, name, kBestEffort) &&
         add_reader(participant, readers, kRosPoseReliable, body, pose, name, kReliable);
    snprintf(name, sizeof name, "rt/panoptes/%s/twist", options->bodies[body]);
    ok = ok && add_reader(participant, readers, kRosTwist, body, &geometry_msgs_msg_dds__TwistStamped__desc,
                          name, kBestEffort);
  }
  return ok &&
         add_reader(participant, readers, kRosTf, -1, &tf2_msgs_msg_dds__TFMessage__desc, "rt/tf",
                    kBestEffort) &&
         add_reader(participant, readers, kRosRigidBodies, -1, &mocap4r2_msgs_msg_dds__RigidBodies__desc,
                    "rt/rigid_bodies", kBestEffort) &&
         add_reader(participant, readers, kRosMarkers, -1, &mocap4r2_msgs_msg_dds__Markers__desc,
                    "rt/markers", kBestEffort);
}

static void dispatch(Capture* capture, const Reader* reader, const void* sample) {
  switch (reader->kind) {
    case kNativePose:
      on_native_pose(capture, sample);
      break;
    case kNativePoseReliable:
      ++capture->native_poses_reliable;
      break;
    case kNativeFrames:
      on_mocap_frame(capture, sample);
      break;
    case kNativeBodyDescriptions:
      on_body_descriptions(capture, sample);
      break;
    case kNativeTracks:
      on_track_frame(capture, sample);
      break;
    case kRosPose:
    case kRosPoseReliable:
      on_ros_pose(capture, reader->body, reader->kind == kRosPoseReliable, sample);
      break;
    case kRosTwist:
      on_ros_twist(capture, reader->body, sample);
      break;
    case kRosTf:
      on_tf(capture, sample);
      break;
    case kRosRigidBodies:
      on_rigid_bodies(capture, sample);
      break;
    case kRosMarkers:
      on_markers(capture, sample);
      break;
  }
}

// Takes everything a reader holds; returns how many samples with data it decoded.
static int drain(Capture* capture, const Reader* reader) {
  int decoded = 0;
  for (;;) {
    void* samples[kTakeBatch] = {NULL};
    dds_sample_info_t infos[kTakeBatch];
    const dds_return_t taken = dds_take(reader->entity, samples, infos, kTakeBatch, kTakeBatch);
    if (taken <= 0) return decoded;
    for (int i = 0; i < taken; ++i) {
      if (!infos[i].valid_data) continue;
      dispatch(capture, reader, samples[i]);
      ++decoded;
    }
    dds_return_loan(reader->entity, samples, taken);
    if (taken < kTakeBatch) return decoded;
  }
}

static void capture_loop(Capture* capture, dds_entity_t participant, const Readers* readers) {
  const dds_entity_t waitset = dds_create_waitset(participant);
  for (int i = 0; i < readers->count; ++i) {
    dds_set_status_mask(readers->items[i].entity, DDS_DATA_AVAILABLE_STATUS);
    dds_waitset_attach(waitset, readers->items[i].entity, i);
  }
  const dds_time_t end = dds_time() + (dds_duration_t)(capture->options->duration_s * 1e9);
  while (dds_time() < end) {
    dds_waitset_wait_until(waitset, NULL, 0, end);
    for (int i = 0; i < readers->count; ++i) drain(capture, &readers->items[i]);
  }
  dds_delete(waitset);
}

// ------------------------------------------------------------------------------------------------
// Checks after the capture.

static int compare_body_time(const void* left, const void* right) {
  const PoseRecord* a = left;
  const PoseRecord* b = right;
  if (a->body != b->body) return a->body < b->body ? -1 : 1;
  if (a->pose_time_ns != b->pose_time_ns) return a->pose_time_ns < b->pose_time_ns ? -1 : 1;
  return 0;
}

static int compare_slice_stamp(const void* left, const void* right) {
  const FrameSlice* a = left;
  const FrameSlice* b = right;
  if (a->stamp_ns != b->stamp_ns) return a->stamp_ns < b->stamp_ns ? -1 : 1;
  return 0;
}

// First record of a sorted list with the key of `key`, or NULL.
static const PoseRecord* find_first(const PoseList* sorted, const PoseRecord* key) {
  size_t low = 0;
  size_t high = sorted->count;
  while (low < high) {
    const size_t middle = low + (high - low) / 2;
    if (compare_body_time(&sorted->items[middle], key) < 0) {
      low = middle + 1;
    } else {
      high = middle;
    }
  }
  if (low == sorted->count || compare_body_time(&sorted->items[low], key) != 0) return NULL;
  return &sorted->items[low];
}

static double max_difference(const double* a, const double* b, int count) {
  double largest = 0.0;
  for (int i = 0; i < count; ++i) largest = fmax(largest, fabs(a[i] - b[i]));
  return largest;
}

// How the records of one topic agree with those of another for the same body and pose time.
typedef struct Agreement {
  uint64_t records;
  uint64_t matched;    // a reference record for the same body and pose time exists
  uint64_t differing;  // ... but none of them has the same values
  double max_difference;
} Agreement;

typedef enum Compared { kComparePose, kCompareVelocities } Compared;

static Agreement agree(const PoseList* subject, const PoseList* sorted_reference, Compared compared) {
  Agreement agreement = {0};
  for (size_t i = 0; i < subject->count; ++i) {
    const PoseRecord* record = &subject->items[i];
    ++agreement.records;
    const PoseRecord* candidate = find_first(sorted_reference, record);
    if (candidate == NULL) continue;
    ++agreement.matched;
    double best = INFINITY;
    const PoseRecord* end = sorted_reference->items + sorted_reference->count;
    for (; candidate != end && compare_body_time(candidate, record) == 0; ++candidate) {
      const double difference =
          compared == kComparePose
              ? fmax(max_difference(candidate->p, record->p, 3), max_difference(candidate->q, record->q, 4))
              : fmax(max_difference(candidate->v, record->v, 3), max_difference(candidate->w, record->w, 3));
      best = fmin(best, difference);
    }
    if (best >= kSameValue) ++agreement.differing;
    agreement.max_difference = fmax(agreement.max_difference, best);
  }
  return agreement;
}

// rt/markers translations that equal a track of the TrackFrame with the same stamp.
static void match_markers_to_tracks(Capture* capture) {
  TrackFrameIndex* tracks = &capture->track_index;
  const TrackFrameIndex* markers = &capture->marker_index;
  if (tracks->frame_count > 0)
    qsort(tracks->frames, tracks->frame_count, sizeof *tracks->frames, compare_slice_stamp);
  for (size_t m = 0; m < markers->frame_count; ++m) {
    const FrameSlice* marker_frame = &markers->frames[m];
    const FrameSlice* track_frame = tracks->frame_count == 0
                                        ? NULL
                                        : bsearch(marker_frame, tracks->frames, tracks->frame_count,
                                                  sizeof *tracks->frames, compare_slice_stamp);
    if (track_frame == NULL) continue;
    ++capture->marker_stats.frames_with_track_frame;
    capture->marker_stats.in_frames_with_track_frame += marker_frame->count;
    for (size_t i = 0; i < marker_frame->count; ++i) {
      const double* marker = markers->positions[marker_frame->first + i];
      for (size_t k = 0; k < track_frame->count; ++k) {
        if (max_difference(tracks->positions[track_frame->first + k], marker, 3) < kSameValue) {
          ++capture->marker_stats.with_track;
          break;
        }
      }
    }
  }
}

static void print_agreement(const char* name, const Agreement* agreement, bool last) {
  printf("      \"%s\": {\"records\": %" PRIu64 ", \"matched\": %" PRIu64 ", \"differing\": %" PRIu64
         ", \"max_difference\": %.3g}%s\n",
         name, agreement->records, agreement->matched, agreement->differing, agreement->max_difference,
         last ? "" : ",");
}

typedef struct RosAgreements {
  Agreement pose_vs_native;
  Agreement twist_vs_native;
  Agreement tf_vs_pose;
  Agreement rigid_bodies_vs_pose;
} RosAgreements;

static bool ros2_checks_hold(const Capture* capture, const RosAgreements* agreements) {
  bool ok = capture->twists > 0 && capture->tf_transforms > 0 && capture->rigid_body_messages > 0 &&
            capture->markers_messages > 0 && capture->marker_stats.markers > 0;
  for (int body = 0; body < capture->options->body_count; ++body) {
    ok = ok && capture->ros_pose_best_effort[body] > 0 && capture->ros_pose_reliable[body] > 0;
  }
  ok = ok && capture->ros_pose_bad_frame == 0 && capture->twist_bad_frame == 0 &&
       capture->tf_bad_parent == 0 && capture->tf_unknown_child == 0 &&
       capture->rigid_bodies_unknown_name == 0 && capture->rigid_body_frames.not_increasing == 0 &&
       capture->marker_frames.not_increasing == 0 && capture->marker_stats.bad_names == 0 &&
       capture->marker_stats.not_finite == 0 && capture->marker_stats.frames_with_track_frame > 0 &&
       capture->marker_stats.with_track == capture->marker_stats.in_frames_with_track_frame;
  const Agreement* all[] = {&agreements->pose_vs_native, &agreements->twist_vs_native,
                            &agreements->tf_vs_pose, &agreements->rigid_bodies_vs_pose};
  for (size_t i = 0; i < sizeof all / sizeof all[0]; ++i)
    ok = ok && all[i]->matched > 0 && all[i]->differing == 0;
  return ok;
}

static void print_ros2_summary(const Capture* capture, const RosAgreements* agreements) {
  printf("  \"ros2\": {\n    \"pose\": {");
  for (int body = 0; body < capture->options->body_count; ++body) {
    printf("%s\"%s\": {\"best_effort\": %" PRIu64 ", \"reliable\": %" PRIu64 "}", body == 0 ? "" : ", ",
           capture->options->bodies[body], capture->ros_pose_best_effort[body],
           capture->ros_pose_reliable[body]);
  }
  printf("},\n    \"pose_bad_frame_id\": %" PRIu64 ",\n", capture->ros_pose_bad_frame);
  printf("    \"twist\": %" PRIu64 ", \"twist_bad_frame_id\": %" PRIu64 ",\n", capture->twists,
         capture->twist_bad_frame);
  printf("    \"tf\": {\"messages\": %" PRIu64 ", \"transforms\": %" PRIu64 ", \"bad_parent\": %" PRIu64
         ", \"unknown_child\": %" PRIu64 "},\n",
         capture->tf_messages, capture->tf_transforms, capture->tf_bad_parent, capture->tf_unknown_child);
  printf("    \"rigid_bodies\": {\"messages\": %" PRIu64 ", \"bodies\": %zu, \"unknown_name\": %" PRIu64
         ", \"frame_number_not_increasing\": %" PRIu64 "},\n",
         capture->rigid_body_messages, capture->rigid_bodies.count, capture->rigid_bodies_unknown_name,
         capture->rigid_body_frames.not_increasing);
  const MarkerStats* markers = &capture->marker_stats;
  printf("    \"markers\": {\"messages\": %" PRIu64 ", \"markers\": %" PRIu64 ", \"labelled\": %" PRIu64
         ", \"bad_names\": %" PRIu64 ", \"not_finite\": %" PRIu64
         ", \"frame_number_not_increasing\": %" PRIu64 ", \"messages_with_track_frame\": %" PRIu64
         ", \"their_markers\": %" PRIu64 ", \"equal_to_a_track\": %" PRIu64 "},\n",
         capture->markers_messages, markers->markers, markers->labelled, markers->bad_names,
         markers->not_finite, capture->marker_frames.not_increasing, markers->frames_with_track_frame,
         markers->in_frames_with_track_frame, markers->with_track);
  printf("    \"agreement\": {\n");
  print_agreement("pose_vs_native_bodies", &agreements->pose_vs_native, false);
  print_agreement("twist_vs_native_bodies", &agreements->twist_vs_native, false);
  print_agreement("tf_vs_pose", &agreements->tf_vs_pose, false);
  print_agreement("rigid_bodies_vs_pose", &agreements->rigid_bodies_vs_pose, true);
  printf("    }\n  },\n");
}

// Prints the JSON summary; returns whether every check held.
static bool report_native(Capture* capture) {
  const Options* options = capture->options;
  bool ok = capture->native_poses > 0 && capture->native_poses_reliable > 0 && capture->tracks > 0 &&
            capture->native_pose_not_finite == 0 && capture->native_poses_unknown_body == 0 &&
            capture->track_not_finite == 0;
  uint64_t per_body[kMaxBodies] = {0};
  for (size_t i = 0; i < capture->native.count; ++i) ++per_body[capture->native.items[i].body];
  printf("  \"native\": {\n    \"bodies\": {\"samples\": %" PRIu64 ", \"reliable\": %" PRIu64
         ", \"unknown_body\": %" PRIu64 ", \"not_finite\": %" PRIu64 ", \"per_body\": {",
         capture->native_poses, capture->native_poses_reliable, capture->native_poses_unknown_body,
         capture->native_pose_not_finite);
  for (int body = 0; body < options->body_count; ++body) {
    printf("%s\"%s\": %" PRIu64, body == 0 ? "" : ", ", options->bodies[body], per_body[body]);
    ok = ok && per_body[body] > 0;
  }
  printf("}},\n    \"tracks\": {\"frames\": %" PRIu64 ", \"tracks\": %" PRIu64 ", \"invalid\": %" PRIu64
         "},\n",
         capture->track_frames, capture->tracks, capture->track_not_finite);
  // rt/panoptes/frames: its tracked bodies' poses are the BodyPoses of the same frame.
  const Agreement frames_vs_bodies = agree(&capture->mocap_bodies, &capture->native, kComparePose);
  printf("    \"frames\": {\"samples\": %" PRIu64 ", \"frame_number_not_increasing\": %" PRIu64
         ", \"unknown_body\": %" PRIu64 ", \"markers\": %" PRIu64 ", \"labelled_markers\": %" PRIu64 "},\n",
         capture->mocap_frames.count, capture->mocap_frames.not_increasing,
         capture->mocap_frame_bodies_unknown, capture->mocap_frame_markers,
         capture->mocap_frame_markers_labelled);
  printf("    \"body_descriptions\": {\"samples\": %" PRIu64 ", \"wrong\": %" PRIu64
         ", \"generation\": %" PRIu64 "},\n",
         capture->body_descriptions, capture->body_descriptions_wrong, capture->body_descriptions_generation);
  printf("    \"agreement\": {\n");
  print_agreement("frames_vs_bodies", &frames_vs_bodies, true);
  printf("    }\n  },\n");
  return ok && capture->mocap_frames.count > 0 && capture->mocap_frames.not_increasing == 0 &&
         capture->mocap_frame_bodies_unknown == 0 && capture->body_descriptions > 0 &&
         capture->body_descriptions_wrong == 0 && frames_vs_bodies.matched > 0 &&
         frames_vs_bodies.differing == 0;
}

// Prints the JSON summary; returns whether every check held.
static bool report(Capture* capture) {
  const Options* options = capture->options;
  PoseList* native = &capture->native;
  qsort(native->items, native->count, sizeof *native->items, compare_body_time);
  printf("{\n  \"domain\": %" PRIu32 ",\n  \"duration_s\": %.3f,\n", options->domain, options->duration_s);
  bool ok = report_native(capture);
  if (options->ros2) {
    PoseList* ros_poses = &capture->ros_poses;
    qsort(ros_poses->items, ros_poses->count, sizeof *ros_poses->items, compare_body_time);
    match_markers_to_tracks(capture);
    const RosAgreements agreements = {
        .pose_vs_native = agree(ros_poses, native, kComparePose),
        .twist_vs_native = agree(&capture->ros_twists, native, kCompareVelocities),
        .tf_vs_pose = agree(&capture->tf, ros_poses, kComparePose),
        .rigid_bodies_vs_pose = agree(&capture->rigid_bodies, ros_poses, kComparePose),
    };
    print_ros2_summary(capture, &agreements);
    ok = ros2_checks_hold(capture, &agreements) && ok;
  }
  printf("  \"ros2_checked\": %s,\n  \"ok\": %s\n}\n", options->ros2 ? "true" : "false",
         ok ? "true" : "false");
  return ok;
}

// ------------------------------------------------------------------------------------------------
// Command line and main.

static void print_help(void) {
  printf(
      "Usage: panoptes_cyclone_probe --bodies NAME[,NAME...] [options]\n"
      "Reads Panoptes' native and ROS 2 topics with Eclipse Cyclone DDS and checks them (docs/interop.md).\n"
      "  --bodies LIST      comma-separated body names (required; at most %d)\n"
      "  --domain N         DDS domain (default: $PANOPTES_DOMAIN, else 0)\n"
      "  --duration S       seconds to read (default 10)\n"
      "  --ros2             also read and check the ROS 2 topics (default: native topics only)\n"
      "  --world-frame ID   frame_id expected in the ROS 2 headers (default world)\n"
      "  --out-dir DIR      write native_poses.jsonl, native_tracks.jsonl and ros2_poses.jsonl there\n"
      "  --config URI       Cyclone DDS configuration (default: $CYCLONEDDS_URI, else\n"
      "                     file://%s)\n"
      "Prints a JSON summary; exit 0 when every topic read had samples and every check held, 1 when not,\n"
      "2 on bad arguments or when DDS cannot start.\n",
      kMaxBodies, PANOPTES_CYCLONE_CONFIG);
}

static bool parse_bodies(Options* options, const char* list) {
  const char* cursor = list;
  while (*cursor != '\0') {
    const size_t length = strcspn(cursor, ",");
    if (length == 0 || length > kMaxNameLength || options->body_count == kMaxBodies) return false;
    char* name = options->bodies[options->body_count++];
    memcpy(name, cursor, length);
    name[length] = '\0';
    // Names become topic names and JSON strings: keep to what both take without escaping.
    if (strspn(name, "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-") != length)
      return false;
    cursor += length;
    if (*cursor == ',') ++cursor;
  }
  return options->body_count > 0;
}

static bool parse_number(const char* text, double minimum, double maximum, double* value) {
  char* end = NULL;
  errno = 0;
  *value = strtod(text, &end);
  return errno == 0 && end != text && *end == '\0' && *value >= minimum && *value <= maximum;
}

// Returns 0 to run, 1 after --help, 2 on a bad argument (the reason printed).
static int parse_options(int argc, char** argv, Options* options) {
  // The rule of panoptes::dds::resolve_domain (docs/protocol.md, "The domain"), which this C
  // program on Cyclone DDS cannot link: unset or empty is 0, anything but an integer 0..232 exits 2.
  const char* domain = getenv("PANOPTES_DOMAIN");
  double number = 0.0;
  options->domain = 0;
  if (domain != NULL && *domain != '\0') {
    if (strspn(domain, "0123456789") != strlen(domain) || !parse_number(domain, 0, 232, &number)) {
      fprintf(stderr, "panoptes_cyclone_probe: PANOPTES_DOMAIN=%s: not a DDS domain id (an integer 0..232)\n",
              domain);
      return 2;
    }
    options->domain = (uint32_t)number;
  }
  options->duration_s = 10.0;
  options->world_frame = "world";
  options->config = getenv("CYCLONEDDS_URI");
  for (int i = 1; i < argc; ++i) {
    const char* flag = argv[i];
    if (strcmp(flag, "--help") == 0 || strcmp(flag, "-h") == 0) {
      print_help();
      return 1;
    }
    if (strcmp(flag, "--ros2") == 0) {
      options->ros2 = true;
      continue;
    }
    if (i + 1 == argc) {
      fprintf(stderr, "panoptes_cyclone_probe: %s needs a value (--help)\n", flag);
      return 2;
    }
    const char* value = argv[++i];
    bool ok = true;
    if (strcmp(flag, "--bodies") == 0) {
      ok = parse_bodies(options, value);
    } else if (strcmp(flag, "--domain") == 0) {
      ok = parse_number(value, 0, 232, &number) && number == floor(number);
      options->domain = (uint32_t)number;
    } else if (strcmp(flag, "--duration") == 0) {
      ok = parse_number(value, 0.1, 3600, &options->duration_s);
    } else if (strcmp(flag, "--world-frame") == 0) {
      options->world_frame = value;
    } else if (strcmp(flag, "--out-dir") == 0) {
      options->out_dir = value;
    } else if (strcmp(flag, "--config") == 0) {
      options->config = value;
    } else {
      fprintf(stderr, "panoptes_cyclone_probe: unknown option %s (--help)\n", flag);
      return 2;
    }
    if (!ok) {
      fprintf(stderr, "panoptes_cyclone_probe: bad value for %s: '%s' (--help)\n", flag, value);
      return 2;
    }
  }
  if (options->body_count == 0) {
    fprintf(stderr, "panoptes_cyclone_probe: --bodies is required (--help)\n");
    return 2;
  }
  return 0;
}

static FILE* open_output(const char* dir, const char* name) {
  if (dir == NULL) return NULL;
  char path[4096];
  snprintf(path, sizeof path, "%s/%s", dir, name);
  FILE* file = fopen(path, "w");
  if (file == NULL) fprintf(stderr, "panoptes_cyclone_probe: %s: cannot open for writing\n", path);
  return file;
}

static void free_capture(Capture* capture) {
  PoseList* lists[] = {&capture->native,     &capture->mocap_bodies, &capture->ros_poses,
                       &capture->ros_twists, &capture->tf,           &capture->rigid_bodies};
  for (size_t i = 0; i < sizeof lists / sizeof lists[0]; ++i) free(lists[i]->items);
  TrackFrameIndex* indexes[] = {&capture->track_index, &capture->marker_index};
  for (size_t i = 0; i < 2; ++i) {
    free(indexes[i]->frames);
    free((void*)indexes[i]->positions);
  }
  FILE* files[] = {capture->native_poses_out, capture->native_tracks_out, capture->ros_poses_out};
  for (size_t i = 0; i < 3; ++i) {
    if (files[i] != NULL) fclose(files[i]);
  }
}

// The configuration given, else the loopback-only one of this checkout: never Cyclone's default,
// which would use every interface and multicast.
static dds_entity_t create_participant(const Options* options) {
  char config[4200];
  if (options->config != NULL && options->config[0] != '\0') {
    snprintf(config, sizeof config, "%s", options->config);
  } else {
    snprintf(config, sizeof config, "file://%s", PANOPTES_CYCLONE_CONFIG);
  }
  const dds_entity_t domain = dds_create_domain(options->domain, config);
  if (domain < 0) {
    fprintf(stderr, "panoptes_cyclone_probe: Cyclone DDS domain %" PRIu32 " with %s: %s\n", options->domain,
            config, dds_strretcode(domain));
    return domain;
  }
  const dds_entity_t participant = dds_create_participant(options->domain, NULL, NULL);
  if (participant < 0) {
    fprintf(stderr, "panoptes_cyclone_probe: participant: %s\n", dds_strretcode(participant));
  }
  return participant;
}

int main(int argc, char** argv) {
  Options options;
  memset(&options, 0, sizeof options);
  const int parsed = parse_options(argc, argv, &options);
  if (parsed != 0) return parsed == 1 ? 0 : 2;
  Capture capture;
  memset(&capture, 0, sizeof capture);
  capture.options = &options;
  capture.native_poses_out = open_output(options.out_dir, "native_poses.jsonl");
  capture.native_tracks_out = open_output(options.out_dir, "native_tracks.jsonl");
  capture.ros_poses_out = options.ros2 ? open_output(options.out_dir, "ros2_poses.jsonl") : NULL;
  if (options.out_dir != NULL && (capture.native_poses_out == NULL || capture.native_tracks_out == NULL ||
                                  (options.ros2 && capture.ros_poses_out == NULL))) {
    free_capture(&capture);
    return 2;
  }
  const dds_entity_t participant = create_participant(&options);
  Readers readers;
  memset(&readers, 0, sizeof readers);
  if (participant < 0 || !create_readers(participant, &options, &readers)) {
    if (participant >= 0) dds_delete(participant);
    free_capture(&capture);
    return 2;
  }
  fprintf(stderr, "panoptes_cyclone_probe: domain %" PRIu32 ", %d readers, reading for %.1f s\n",
          options.domain, readers.count, options.duration_s);
  capture_loop(&capture, participant, &readers);
  // The summary first: a secured participant's teardown once ended the process under load with
  // nothing printed, though every pose had been read (test_cyclone_security in a fresh clone).
  const bool ok = report(&capture);
  fflush(stdout);
  dds_delete(participant);
  free_capture(&capture);
  return ok ? 0 : 1;
}
