// Internal to pbppo::dds: the Fast DDS type of a robot's message, from its IDL (no generated
// code). Its samples are CdrSample objects: the plain CDR bytes as they travel (cdr.hpp), copied
// as they are to and from the wire (a message with strings or sequences: written in its layout,
// read into it by NormalizeCdrSample).
#pragma once

#include <fastdds/dds/topic/TopicDataType.hpp>
#include <memory>
#include <string>

#include "runtime/robot/idl.hpp"

namespace pbppo::dds {

// A sample as Fast DDS hands it to serialize / fills it in deserialize: `bytes` holds
// CdrSampleBytes of the type; `ok` says whether the last deserialize gave one (false: another
// size or encoding, nothing copied).
struct CdrSample {
  std::byte* bytes = nullptr;
  bool ok = false;
};

class CdrTopicType final : public eprosima::fastdds::dds::TopicDataType {
 public:
  CdrTopicType(const std::string& wire_name, const robot::IdlMessage& type);

  bool serialize(void* data, eprosima::fastrtps::rtps::SerializedPayload_t* payload) override;
  bool deserialize(eprosima::fastrtps::rtps::SerializedPayload_t* payload, void* data) override;
  std::function<std::uint32_t()> getSerializedSizeProvider(void* data) override;
  void* createData() override;
  void deleteData(void* data) override;
  bool getKey(void* data, eprosima::fastrtps::rtps::InstanceHandle_t* handle, bool force_md5) override;
  bool is_bounded() const override { return !type_->variable(); }

 private:
  const robot::IdlMessage* type_;  // the robot model's, which outlives the participant's topics
  std::uint32_t bytes_ = 0;        // header and data (a message with strings or sequences: its layout's)
};

}  // namespace pbppo::dds
