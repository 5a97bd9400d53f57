#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>

#include <fastcdr/exceptions/Exception.h>
#include <fastdds/rtps/common/SerializedPayload.h>

namespace mrslam::fuzz {

// Decodes bytes as the CDR payload of a DDS sample of PubSubType's message, as a reader would
// receive it from any writer. False when they do not decode (the generated deserializer reports
// some malformed payloads by a Fast CDR exception rather than false: those are the middleware's
// to handle before a sample reaches the project's code, and are not what is fuzzed here).
template <typename PubSubType>
bool Decode(const std::uint8_t* data, std::size_t size, typename PubSubType::type* out) {
  eprosima::fastrtps::rtps::SerializedPayload_t payload(static_cast<std::uint32_t>(size));
  if (size > 0) std::memcpy(payload.data, data, size);
  payload.length = static_cast<std::uint32_t>(size);
  PubSubType type;
  try {
    return type.deserialize(&payload, out);
  } catch (const eprosima::fastcdr::exception::Exception&) {
    return false;
  }
}

}  // namespace mrslam::fuzz
