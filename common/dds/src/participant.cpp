// SPDX-License-Identifier: Apache-2.0
// The participant: the XML profile, DDS Security, the domain, shared-memory ports, and the Bus
// that owns it.
#include "participant.h"

#include <dlfcn.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <iterator>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <vector>

#include <fastdds/rtps/attributes/PropertyPolicy.h>
#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>
#include <fastdds/rtps/transport/shared_mem/SharedMemTransportDescriptor.h>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/log/Log.hpp>

#include "panoptes/dds/domain.h"
#include "panoptes/dds/shm_ports.h"

namespace panoptes::dds {
namespace {

std::filesystem::path executable_dir() {
  std::vector<char> buffer(4096);
  const ssize_t n = readlink("/proc/self/exe", buffer.data(), buffer.size() - 1);
  if (n <= 0) return {};
  return std::filesystem::path(std::string(buffer.data(), static_cast<std::size_t>(n))).parent_path();
}

// The directory of the binary holding this code: the executable, or a shared library that links
// panoptes_dds (libpanoptes_client.so in <prefix>/lib, used by programs installed anywhere).
std::filesystem::path module_dir() {
  Dl_info info{};
  if (dladdr(reinterpret_cast<const void*>(&module_dir), &info) == 0 || info.dli_fname == nullptr) return {};
  return std::filesystem::path(info.dli_fname).parent_path();
}

}  // namespace

std::filesystem::path resolve_profile_file(const std::filesystem::path& requested) {
  if (!requested.empty()) {
    if (!std::filesystem::is_regular_file(requested)) {
      throw DdsInputError("DDS profile " + requested.string() + ": no such file");
    }
    return requested;
  }
  if (const char* env = std::getenv("PANOPTES_DDS_PROFILE"); env != nullptr && *env != '\0') {
    if (!std::filesystem::is_regular_file(env)) {
      throw DdsInputError(std::string("PANOPTES_DDS_PROFILE=") + env + ": no such file");
    }
    return env;
  }
  const std::filesystem::path exe = executable_dir();
  const std::vector<std::filesystem::path> candidates = {
      exe / "../../deploy/dds/loopback.xml",                // build/bin in a source checkout
      exe / "../share/panoptes/dds/loopback.xml",           // installed prefix
      module_dir() / "../share/panoptes/dds/loopback.xml",  // <prefix>/lib/libpanoptes_client.so
      std::filesystem::path(PANOPTES_INSTALL_DATADIR) / "panoptes/dds/loopback.xml",  // configured prefix
      std::filesystem::path(PANOPTES_SOURCE_DIR) / "deploy/dds/loopback.xml",  // a build tree elsewhere
  };
  for (const auto& candidate : candidates) {
    if (std::filesystem::is_regular_file(candidate)) return std::filesystem::weakly_canonical(candidate);
  }
  std::string tried;
  for (const auto& candidate : candidates) (tried += ' ') += candidate.lexically_normal().string();
  throw DdsInputError("no DDS profile given (--dds-profile or PANOPTES_DDS_PROFILE) and none found at:" +
                      tried);
}

ReturnCode return_code_ok() {
  return ReturnCode::RETCODE_OK;
}

namespace {

// The profile asks for DDS Security with the participant property panoptes.security=required.
bool profile_requires_security(const fdds::DomainParticipantQos& qos) {
  const std::string* value =
      eprosima::fastrtps::rtps::PropertyPolicyHelper::find_property(qos.properties(), "panoptes.security");
  return value != nullptr && *value == "required";
}

// Adds the DDS Security properties to `qos` when `options` (or the environment) name security
// files, after checking them; nullopt for an unsecured participant. SecurityError for bad files and
// for a profile that requires security without them.
std::optional<SecurityFiles> apply_security(const BusOptions& options, const std::filesystem::path& profile,
                                            int domain, fdds::DomainParticipantQos& qos) {
  std::optional<SecurityFiles> files = resolve_security_files(options.security);
  if (!files) {
    if (profile_requires_security(qos))
      throw SecurityError(profile.string(), "panoptes.security",
                          "the profile requires DDS Security: give --security-dir and --security-identity "
                          "(or PANOPTES_SECURITY_DIR and PANOPTES_SECURITY_IDENTITY)");
    return std::nullopt;
  }
  check_security_files(*files);
  check_security_domain(*files, domain);
  for (const auto& [name, value] : security_properties(*files))
    qos.properties().properties().emplace_back(name, value);
  return files;
}

// Where Fast DDS 2.9 keeps its shared-memory segments and their lock files on Linux.
constexpr const char* kShmDir = "/dev/shm";
constexpr const char* kProcDir = "/proc";
// Participant ids tried for one without an initial-peer range (discovery by multicast or server).
constexpr int kParticipantIdLimit = 120;

bool uses_shared_memory(const fdds::DomainParticipantQos& qos) {
  if (qos.transport().use_builtin_transports) return true;
  for (const auto& transport : qos.transport().user_transports) {
    if (std::dynamic_pointer_cast<eprosima::fastdds::rtps::SharedMemTransportDescriptor>(transport))
      return true;
  }
  return false;
}

// BusOptions::shared_memory false: the profile's transports without shared memory. Fast DDS's
// builtin transports (UDPv4 and shared memory) become an explicit UDPv4 transport. A profile with
// no other transport (deploy/dds/shm.xml: one host, no socket) keeps it.
void leave_out_shared_memory(fdds::DomainParticipantQos& qos) {
  auto& transport = qos.transport();
  const auto is_shared_memory = [](const auto& descriptor) {
    return std::dynamic_pointer_cast<eprosima::fastdds::rtps::SharedMemTransportDescriptor>(descriptor) !=
           nullptr;
  };
  if (transport.use_builtin_transports) {
    transport.use_builtin_transports = false;
    transport.user_transports.push_back(
        std::make_shared<eprosima::fastdds::rtps::UDPv4TransportDescriptor>());
  }
  if (std::all_of(transport.user_transports.begin(), transport.user_transports.end(), is_shared_memory))
    return;
  std::erase_if(transport.user_transports, is_shared_memory);
}

// The ids a participant can take and still be found: with initial peers, those whose ports the
// UDP transports probe (maxInitialPeersRange).
int participant_id_limit(const fdds::DomainParticipantQos& qos) {
  int limit = kParticipantIdLimit;
  if (qos.wire_protocol().builtin.initialPeersList.empty()) return limit;
  if (qos.transport().use_builtin_transports)
    limit = std::min(
        limit, static_cast<int>(eprosima::fastdds::rtps::UDPv4TransportDescriptor().maxInitialPeersRange));
  for (const auto& transport : qos.transport().user_transports) {
    if (std::dynamic_pointer_cast<eprosima::fastdds::rtps::UDPv4TransportDescriptor>(transport))
      limit = std::min(limit, static_cast<int>(transport->maxInitialPeersRange));
  }
  return limit;
}

// The participant ids this process chose before, with the order of their last use (shm_ports.h:
// an id used again gives the new participant the old one's GUID). Guarded by
// participant_creation_mutex().
std::map<int, std::uint64_t>& ids_used_before() {
  static std::map<int, std::uint64_t> ids;
  return ids;
}
std::uint64_t& participants_created() {
  static std::uint64_t count = 0;
  return count;
}

// Keeps a participant off ids this process used before (their GUIDs, shm_ports.h), off the
// shared-memory ports of participants killed on this host, and off those a process still maps
// after they were removed (shm_ports.h):
// taking one would cut it off from every writer that still maps the killed one's segment (a console
// restarted after SIGKILL received no FeatureFrame from some or all cameras). An id the profile sets
// is kept; when every id is taken, Fast DDS chooses as before.
void keep_off_killed_participants_ports(fdds::DomainParticipantQos& qos, std::uint32_t domain) {
  auto& wire = qos.wire_protocol();
  if (wire.participant_id >= 0 || !uses_shared_memory(qos)) return;
  const ParticipantPortRule rule{wire.port.portBase, wire.port.domainIDGain, wire.port.participantIDGain,
                                 wire.port.offsetd1, wire.port.offsetd3};
  if (const auto id = participant_id_clear_of_owned_shm_ports(
          rule, domain, participant_id_limit(qos), kShmDir, shm_ports_mapped_after_removal(kProcDir),
          ids_used_before())) {
    wire.participant_id = *id;
    ids_used_before()[*id] = ++participants_created();
  }
}

constexpr const char* kProcSelfFdDir = "/proc/self/fd";

// The segment a participant created: the one segment lock this process holds after creating it and
// did not before (participant_creation_mutex() held); empty when there is none or more than one.
std::string created_segment(const std::set<std::string>& before, const std::set<std::string>& after) {
  std::vector<std::string> added;
  std::set_difference(after.begin(), after.end(), before.begin(), before.end(), std::back_inserter(added));
  return added.size() == 1 ? added.front() : std::string();
}

// Held from choosing a participant id until its ports exist: two buses of one process never take
// the same id.
std::mutex& participant_creation_mutex() {
  static std::mutex mutex;
  return mutex;
}

}  // namespace

BusCore::BusCore(const BusOptions& options) {
  const int domain = resolve_domain(options.domain_id);
  profile_file_ = resolve_profile_file(options.profile_file);
  auto* factory = fdds::DomainParticipantFactory::get_instance();
  if (factory->load_XML_profiles_file(profile_file_.string()) != return_code_ok()) {
    throw DdsInputError("DDS profile " + profile_file_.string() + ": cannot be parsed");
  }
  fdds::DomainParticipantQos qos;
  if (factory->get_participant_qos_from_profile(options.participant_profile, qos) != return_code_ok()) {
    throw DdsInputError("DDS profile " + profile_file_.string() + ": no participant profile named '" +
                        options.participant_profile + "'");
  }
  qos.name(options.participant_name);
  security_files_ = apply_security(options, profile_file_, domain, qos);
  create_entities(domain, qos, options.shared_memory);
}

void BusCore::create_entities(int domain, fdds::DomainParticipantQos& qos, bool shared_memory) {
  {
    std::lock_guard<std::mutex> lock(participant_creation_mutex());
    // Chosen with the profile's transports, shared memory included, and only then without it: a
    // participant left to Fast DDS's own choice of id could take one this process chooses next
    // for another ("RTPSParticipant with the same ID already exists").
    keep_off_killed_participants_ports(qos, static_cast<std::uint32_t>(domain));
    if (!shared_memory) leave_out_shared_memory(qos);
    const std::set<std::string> segments_before = shm_segments_held(kProcSelfFdDir);
    participant_ = fdds::DomainParticipantFactory::get_instance()->create_participant(
        static_cast<fdds::DomainId_t>(domain), qos, &listener_, fdds::StatusMask::none());
    shm_segment_ = created_segment(segments_before, shm_segments_held(kProcSelfFdDir));
  }
  if (participant_ == nullptr && security_files_) {
    fdds::Log::Flush();  // Fast DDS's own reason, logged asynchronously, goes out before ours
    throw SecurityError(security_files_->certificate.string(), "",
                        "DDS Security refused to create the participant (domain " + std::to_string(domain) +
                            "): a certificate not signed by the identity CA, expired or revoked, a key that "
                            "does not match it, or a governance or permissions document not signed by the "
                            "permissions CA or not granting this domain and subject (Fast DDS's reason is "
                            "logged above). Files: " +
                            describe_security_files(*security_files_));
  }
  if (participant_ == nullptr)
    throw DdsError("cannot create DDS participant (domain " + std::to_string(domain) + ")");
  if (participant_->register_content_filter_factory(kIdFilterClass, &leading_id_filter_factory()) !=
      return_code_ok()) {
    teardown();
    throw DdsError("cannot register the DDS content filter " + std::string(kIdFilterClass));
  }
  publisher_ = participant_->create_publisher(fdds::PUBLISHER_QOS_DEFAULT);
  subscriber_ = participant_->create_subscriber(fdds::SUBSCRIBER_QOS_DEFAULT);
  if (publisher_ == nullptr || subscriber_ == nullptr) {
    teardown();
    throw DdsError("cannot create DDS publisher/subscriber");
  }
}

void BusCore::teardown() {
  if (participant_ == nullptr) return;
  participant_->delete_contained_entities();
  // Its samples other processes on this host have not read yet stay readable (shm_ports.h).
  // Only processes of this host read them, and only those that found it may hold one.
  const bool kept = !shm_segment_.empty() &&
                    listener_.discovered_another_process_on_host_of(participant_->guid().guidPrefix) &&
                    keep_shm_segment_name(kShmDir, shm_segment_);
  fdds::DomainParticipantFactory::get_instance()->delete_participant(participant_);
  participant_ = nullptr;
  if (kept) restore_shm_segment_name(kShmDir, shm_segment_);
}

fdds::Topic* BusCore::topic_of_type(const std::string& name,
                                    const std::function<fdds::TypeSupport()>& make_type) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (auto it = topics_.find(name); it != topics_.end()) return it->second;
  fdds::TypeSupport type = make_type();
  if (type.register_type(participant_) != return_code_ok()) {
    throw DdsError("cannot register DDS type for " + name);
  }
  fdds::Topic* topic = participant_->create_topic(name, type.get_type_name(), fdds::TOPIC_QOS_DEFAULT);
  if (topic == nullptr) throw DdsError("cannot create DDS topic " + name + refusal_hint());
  topics_.emplace(name, topic);
  return topic;
}

void BusCore::delete_filtered_topic(fdds::ContentFilteredTopic* topic) {
  std::lock_guard<std::mutex> lock(mutex_);
  participant_->delete_contentfilteredtopic(topic);
}

void ParticipantListener::on_participant_discovery(
    fdds::DomainParticipant*, eprosima::fastrtps::rtps::ParticipantDiscoveryInfo&& info) {
  if (info.status != eprosima::fastrtps::rtps::ParticipantDiscoveryInfo::DISCOVERED_PARTICIPANT) return;
  ProcessKey key{};
  std::copy_n(info.info.m_guid.guidPrefix.value, key.size(), key.begin());
  std::lock_guard<std::mutex> lock(mutex_);
  processes_.insert(key);
}

bool ParticipantListener::discovered_another_process_on_host_of(
    const eprosima::fastrtps::rtps::GuidPrefix_t& own) const {
  constexpr std::size_t kHostEnd = 4;  // vendor and host
  std::lock_guard<std::mutex> lock(mutex_);
  return std::any_of(processes_.begin(), processes_.end(), [&](const ProcessKey& process) {
    return std::equal(process.begin(), process.begin() + kHostEnd, own.value) &&
           !std::equal(process.begin() + kHostEnd, process.end(), own.value + kHostEnd);
  });
}

// ---------------------------------------------------------------------------------------------
// Bus

Bus::Bus(const BusOptions& options) : core_(std::make_shared<BusCore>(options)) {}
Bus::~Bus() = default;

const std::filesystem::path& Bus::profile_file() const {
  return core_->profile_file();
}

std::map<std::string, std::uint64_t> Bus::receive_rejections() const {
  return core_->receive_counters().snapshot();
}

bool Bus::secured() const {
  return core_->secured();
}

}  // namespace panoptes::dds
