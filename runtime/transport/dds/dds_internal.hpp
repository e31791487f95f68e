// Internal to pbppo::dds: the participant's Fast DDS entities, QoS, and the errors of the DDS
// transport.
#pragma once

#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/publisher/qos/DataWriterQos.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/subscriber/qos/DataReaderQos.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>
#include <map>
#include <mutex>
#include <string>

#include "runtime/transport/dds/dds_endpoint.hpp"

namespace pbppo::dds {

namespace fdds = eprosima::fastdds::dds;

struct DdsParticipant::Impl {
  int domain_id = 0;
  fdds::DomainParticipant* participant = nullptr;
  fdds::Publisher* publisher = nullptr;
  fdds::Subscriber* subscriber = nullptr;
  std::mutex topics_mu;
  std::map<std::string, fdds::Topic*> topics;
  ~Impl();
  // The topic `name` of the message `type` (its type registered under `type_name`, or the IDL's
  // name when empty; the topic created once); null on failure.
  fdds::Topic* TopicFor(const std::string& name, const robot::IdlMessage& type, const std::string& type_name);
};

// Reliable, transient-local, keep-last `depth`, no data-sharing (dds_participant.cpp says why).
fdds::DataWriterQos WriterQos(std::int32_t depth);
fdds::DataReaderQos ReaderQos(std::int32_t depth, bool transient_local);
Error DdsError(const std::string& what);

}  // namespace pbppo::dds
