#include "runtime/transport/dds/cdr_type.hpp"

#include <algorithm>
#include <cstring>

#include "runtime/transport/dds/cdr.hpp"

namespace pbppo::dds {

CdrTopicType::CdrTopicType(const std::string& wire_name, const robot::IdlMessage& type)
    : type_(&type), bytes_(static_cast<std::uint32_t>(CdrSampleBytes(type))) {
  setName(wire_name.c_str());
  // The payload's room: the data padded to 4 bytes (a sender may pad), and the header; a message
  // with strings or sequences takes samples up to kMaxWireSampleBytes.
  m_typeSize = type.variable() ? static_cast<std::uint32_t>(std::max<std::size_t>(kMaxWireSampleBytes, bytes_ + 3u))
                               : static_cast<std::uint32_t>((type.cdr_size + 3u) / 4u * 4u + kCdrHeaderBytes);
  m_isGetKeyDefined = false;
  auto_fill_type_object(false);
  auto_fill_type_information(false);
}

bool CdrTopicType::serialize(void* data, eprosima::fastrtps::rtps::SerializedPayload_t* payload) {
  const auto* s = static_cast<const CdrSample*>(data);
  if (payload->max_size < bytes_) return false;
  std::memcpy(payload->data, s->bytes, bytes_);
  payload->length = bytes_;
  payload->encapsulation = s->bytes[1] == std::byte{0x00} ? CDR_BE : CDR_LE;
  return true;
}

bool CdrTopicType::deserialize(eprosima::fastrtps::rtps::SerializedPayload_t* payload, void* data) {
  auto* s = static_cast<CdrSample*>(data);
  bool big_endian = false;
  if (type_->variable()) {
    s->ok = NormalizeCdrSample(*type_, reinterpret_cast<const std::byte*>(payload->data), payload->length, s->bytes);
    return true;
  }
  // Exactly the IDL's size, or padded to 4 bytes as some senders do; plain CDR only.
  s->ok = payload->length >= bytes_ && payload->length <= (bytes_ + 3u) / 4u * 4u &&
          ReadCdrHeader(reinterpret_cast<const std::byte*>(payload->data), &big_endian);
  if (s->ok) std::memcpy(s->bytes, payload->data, bytes_);
  return true;
}

std::function<std::uint32_t()> CdrTopicType::getSerializedSizeProvider(void*) {
  return [n = bytes_] { return n; };
}

void* CdrTopicType::createData() {
  auto* s = new CdrSample;
  s->bytes = new std::byte[bytes_]();
  return s;
}

void CdrTopicType::deleteData(void* data) {
  auto* s = static_cast<CdrSample*>(data);
  delete[] s->bytes;
  delete s;
}

bool CdrTopicType::getKey(void*, eprosima::fastrtps::rtps::InstanceHandle_t*, bool) {
  return false;
}

}  // namespace pbppo::dds
