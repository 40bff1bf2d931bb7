// SPDX-License-Identifier: Apache-2.0
#include "panoptes/estimator_app/recording_input.h"

#include "panoptes/dds/cdr.h"
#include "panoptes/dds/convert.h"
#include "panoptes/recording/mcap_reader.h"
#include "panoptes/session/log.h"

namespace panoptes::estimator_app {

namespace {
constexpr const char* kFeatureTopic = "/panoptes/features";
constexpr std::size_t kLoggedProblems = 5;
}  // namespace

session::FeatureFiles read_recording_features(const std::string& path) {
  session::FeatureFiles files;
  recording::McapReader reader(path);
  std::uint64_t index = 0;
  std::size_t undecodable = 0;
  const auto report = reader.read([&](const recording::MessageView& m) {
    ++index;
    if (m.channel->topic != kFeatureTopic) return;
    msg::FeatureFrame message;
    if (!dds::decode_cdr(m.data, message)) {
      if (++undecodable <= kLoggedProblems)
        session::log(path + ": message " + std::to_string(index) + " on " + kFeatureTopic +
                     ": cannot decode its CDR: skipped");
      return;
    }
    FeatureFrame frame = dds::from_message(message);
    frame.received_ns = static_cast<TimeNs>(m.log_time);
    files.frames.push_back(std::move(frame));
  });
  for (const auto& problem : report.problems) session::log(problem);
  files.bad_lines = undecodable + report.chunks_skipped + report.records_skipped;
  return files;
}

}  // namespace panoptes::estimator_app
