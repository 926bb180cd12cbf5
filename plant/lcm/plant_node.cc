#include "plant_node.h"

#include "fralab/lcm_io.h"

namespace fralab {

PlantNode::PlantNode(lcm::LCM& data, lcm::LCM& control, LockstepPlant plant)
    : plant_(std::move(plant)), data_(data), control_(control) {
  data_.subscribe(kCmdChannel, &PlantNode::on_command, this)->setQueueCapacity(100000);
}

void PlantNode::announce_ready() { ack(-1); }

void PlantNode::ack(int64_t seq) {
  ack_t a;
  a.run_id = plant_.run_id();
  a.consumer = "plant";
  a.seq = seq;
  control_.publish(kAckChannel, &a);
}

void PlantNode::on_command(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
  if (plant_.done() || !error_.empty()) return;
  try {
    const Block cmd = from_msg(decode_checked<command_block_t>(rbuf, channel));
    if (!plant_.accepts(cmd.run_id)) return;  // another run on the same URL: not ours
    tape_block_t msg = to_tape_msg(plant_.advance(cmd));
    started_ = true;
    data_.publish(kTapeChannel, &msg);
    ack(cmd.seq);
  } catch (const std::exception& e) {
    error_ = e.what();
  }
}

}  // namespace fralab
