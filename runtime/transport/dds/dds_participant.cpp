#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fstream>
#include <set>
#include <sstream>

#include "runtime/transport/dds/cdr_type.hpp"
#include "runtime/transport/dds/dds_internal.hpp"
#include "runtime/transport/dds/dds_security.hpp"

namespace pbppo::dds {

using eprosima::fastrtps::types::ReturnCode_t;

Error DdsError(const std::string& what) {
  return MakeError(ErrorCode::kInvalidValue, "dds: " + what);
}

// Reliable, and transient-local: discovery is not symmetric (our writer may know a reader before
// that reader knows our writer, and a volatile reader drops what was written before it matched),
// so the first lock-step sample or command written right after matching would otherwise be lost.
// A reader that joins late gets the writer's last `depth` messages.
fdds::DataWriterQos WriterQos(std::int32_t depth) {
  fdds::DataWriterQos q = fdds::DATAWRITER_QOS_DEFAULT;
  q.reliability().kind = fdds::RELIABLE_RELIABILITY_QOS;
  q.durability().kind = fdds::TRANSIENT_LOCAL_DURABILITY_QOS;
  q.history().kind = fdds::KEEP_LAST_HISTORY_QOS;
  q.history().depth = depth;
  q.publish_mode().kind = fdds::SYNCHRONOUS_PUBLISH_MODE;
  q.data_sharing().off();  // see ReaderQos
  return q;
}

fdds::DataReaderQos ReaderQos(std::int32_t depth, bool transient_local) {
  fdds::DataReaderQos q = fdds::DATAREADER_QOS_DEFAULT;
  q.reliability().kind = fdds::RELIABLE_RELIABILITY_QOS;
  q.durability().kind = transient_local ? fdds::TRANSIENT_LOCAL_DURABILITY_QOS : fdds::VOLATILE_DURABILITY_QOS;
  q.history().kind = fdds::KEEP_LAST_HISTORY_QOS;
  q.history().depth = depth;
  // No data-sharing (shared-memory delivery between participants on one host): Fast DDS 2.9's
  // DataSharingListener can spin forever on a sample it rejects, and deleting the reader then
  // hangs joining that thread (seen here: a test process at 100 % CPU in
  // DataSharingListener::process_new_data while ~DataReaderImpl waited; fixed upstream in
  // eProsima/Fast-DDS#6490, not in Debian's 2.9). Samples take the loopback UDP transport of the
  // profile, like between machines.
  q.data_sharing().off();
  return q;
}

Result<DdsNaming> ParseDdsNaming(const std::string& text) {
  if (text == "native") return DdsNaming::kNative;
  if (text == "ros2") return DdsNaming::kRos2;
  return DdsError("naming '" + text + "': expected native or ros2");
}

const char* ToString(DdsNaming naming) noexcept {
  return naming == DdsNaming::kRos2 ? "ros2" : "native";
}

std::string WireTopic(DdsNaming naming, const std::string& topic) {
  return naming == DdsNaming::kRos2 ? "rt/" + topic : topic;
}

std::string WireTypeName(DdsNaming naming, const std::string& idl_name, const std::string& ros2_message) {
  return naming == DdsNaming::kRos2 ? "pbppo_msgs::msg::dds_::" + ros2_message + "_" : idl_name;
}

DdsParticipant::Impl::~Impl() {
  if (participant == nullptr) return;
  participant->delete_contained_entities();
  fdds::DomainParticipantFactory::get_instance()->delete_participant(participant);
}

fdds::Topic* DdsParticipant::Impl::TopicFor(const std::string& name, const robot::IdlMessage& message,
                                            const std::string& type_name) {
  std::lock_guard<std::mutex> lk(topics_mu);
  if (const auto it = topics.find(name); it != topics.end()) return it->second;
  const std::string registered = type_name.empty() ? message.type_name : type_name;
  fdds::TypeSupport type(new CdrTopicType(registered, message));
  if (type.register_type(participant, registered) != ReturnCode_t::RETCODE_OK) return nullptr;
  fdds::Topic* t = participant->create_topic(name, registered, fdds::TOPIC_QOS_DEFAULT);
  if (t != nullptr) topics[name] = t;
  return t;
}

Result<std::unique_ptr<DdsParticipant>> DdsParticipant::Create(const DdsOptions& o) {
  if (o.domain_id < 0 || o.domain_id > 232)
    return DdsError("domain_id " + std::to_string(o.domain_id) + " is outside 0..232");
  std::string xml = o.profile_xml;
  std::string origin = "the robot's profile";
  if (xml.empty()) {
    std::ifstream f(o.profile_file, std::ios::binary);
    if (!f) return MakeError(ErrorCode::kIo, "dds: profile_file '" + o.profile_file + "' cannot be read");
    std::ostringstream text;
    text << f.rdbuf();
    xml = text.str();
    origin = "profile_file '" + o.profile_file + "'";
  }
  auto* factory = fdds::DomainParticipantFactory::get_instance();
  // Each text of profiles is loaded once per process (a second load only makes Fast DDS log that
  // the names exist); profiles Fast DDS cannot parse make the lookup below fail, which names both.
  static std::mutex loaded_mu;
  static std::set<std::string> loaded_texts;
  bool loaded = true;
  {
    std::lock_guard<std::mutex> lk(loaded_mu);
    if (loaded_texts.count(xml) == 0) {
      loaded = factory->load_XML_profiles_string(xml.data(), xml.size()) == ReturnCode_t::RETCODE_OK;
      if (loaded) loaded_texts.insert(xml);
    }
  }
  auto impl = std::make_unique<Impl>();
  impl->domain_id = o.domain_id;
  fdds::DomainParticipantQos qos;
  if (factory->get_participant_qos_from_profile(o.participant_profile, qos) != ReturnCode_t::RETCODE_OK)
    return DdsError("participant_profile '" + o.participant_profile + "' from " + origin +
                    (loaded ? "" : " (the profiles did not load)") + ": no such participant profile");
  if (o.security.enabled()) {
    if (auto st = CheckDdsSecurity(o.security); !st) return st.error();
    for (const auto& [name, value] : SecurityProperties(o.security))
      qos.properties().properties().emplace_back(name, value);
  }
  impl->participant = factory->create_participant(static_cast<fdds::DomainId_t>(o.domain_id), qos);
  if (impl->participant == nullptr)
    return DdsError("participant_profile '" + o.participant_profile + "' from " + origin +
                    ": no participant on domain " + std::to_string(o.domain_id) +
                    (o.security.enabled() ? " (Fast DDS refused the security of identity '" + o.security.identity +
                                                "' in " + o.security.dir + ")"
                                          : std::string()));
  impl->publisher = impl->participant->create_publisher(fdds::PUBLISHER_QOS_DEFAULT);
  impl->subscriber = impl->participant->create_subscriber(fdds::SUBSCRIBER_QOS_DEFAULT);
  if (impl->publisher == nullptr || impl->subscriber == nullptr) return DdsError("cannot create publisher/subscriber");
  return std::unique_ptr<DdsParticipant>(new DdsParticipant(std::move(impl)));
}

DdsParticipant::DdsParticipant(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
DdsParticipant::~DdsParticipant() = default;

int DdsParticipant::domain_id() const noexcept {
  return impl_->domain_id;
}

}  // namespace pbppo::dds
