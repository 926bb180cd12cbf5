// The LCM channels of a lab run (docs/lcm-protocol.md): the commands, the tape, the status events
// and the acknowledgements, the analysers' curves and the identifier's fits.
#pragma once

namespace fralab {

inline constexpr const char* kCmdChannel = "FRALAB_CMD";
inline constexpr const char* kTapeChannel = "FRALAB_TAPE";
inline constexpr const char* kStatusChannel = "FRALAB_STATUS";
inline constexpr const char* kAckChannel = "FRALAB_ACK";
inline constexpr const char* kFrdChannel = "FRALAB_FRD";
inline constexpr const char* kTfChannel = "FRALAB_TF";
// On the data URL (not the control URL, whose every acknowledgement each listener would have to
// read: 28 analysers x 30 acknowledgements a block): the acquisition's flow requests, and the
// identifier's acknowledgements of complete curves.
inline constexpr const char* kFlowChannel = "FRALAB_FLOW";
inline constexpr const char* kFrdAckChannel = "FRALAB_FRD_ACK";

}  // namespace fralab
