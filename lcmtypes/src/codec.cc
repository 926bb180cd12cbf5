#include "fralab/lcm/codec.h"

#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "fralab/core/measurement_chain.h"
#include "fralab/core/text.h"

namespace fralab {

template <class Msg>
static Msg to_msg(const Block& b) {
  Msg m;
  m.run_id = b.run_id;
  m.seq = b.seq;
  m.start_sample = b.start_sample;
  m.sample_rate_hz = b.sample_rate_hz;
  m.n_channels = static_cast<int32_t>(b.channels.size());
  m.channel_names = b.channels;
  m.n_samples = b.n_samples;
  m.n_values = static_cast<int32_t>(b.samples.size());
  m.samples = b.samples;
  m.final_block = b.final_block;
  return m;
}

template <class Msg>
static Block from(const Msg& m, const char* type) {
  if (m.n_channels < 0 || m.n_samples < 0 ||
      int64_t(m.n_values) != int64_t(m.n_channels) * m.n_samples) {
    throw InputError(std::string("fralab.") + type + " seq " + std::to_string(m.seq) +
                     ": n_values " + std::to_string(m.n_values) + " != n_channels " +
                     std::to_string(m.n_channels) + " * n_samples " + std::to_string(m.n_samples));
  }
  if (!(m.sample_rate_hz > 0.0) || !std::isfinite(m.sample_rate_hz)) {
    throw InputError(std::string("fralab.") + type + " seq " + std::to_string(m.seq) +
                     ": sample_rate_hz must be a finite > 0");
  }
  // No lab run reaches 10^13 samples (300 years at 1 kHz) or blocks of 10^7: a corrupt record.
  if (m.start_sample < 0 || m.start_sample > 10000000000000LL || m.n_samples > 10000000) {
    throw InputError(std::string("fralab.") + type + " seq " + std::to_string(m.seq) +
                     ": start_sample " + std::to_string(m.start_sample) + ", n_samples " +
                     std::to_string(m.n_samples) + " are not a block of a run (corrupt)");
  }
  Block b;
  b.run_id = m.run_id;
  b.seq = m.seq;
  b.start_sample = m.start_sample;
  b.sample_rate_hz = m.sample_rate_hz;
  b.channels = m.channel_names;
  b.n_samples = m.n_samples;
  b.samples = m.samples;
  b.final_block = m.final_block;
  return b;
}

namespace {

int64_t crc_of(tape_block_t m) {
  m.crc32 = 0;
  std::vector<uint8_t> buf(size_t(m.getEncodedSize()));
  m.encode(buf.data(), 0, int(buf.size()));
  return int64_t(::crc32(::crc32(0L, Z_NULL, 0), buf.data(), uInt(buf.size())));
}

// A walk over the wire format of the messages read from files, with bounds: LCM's generated
// decoders size their arrays from the counts in the bytes before checking that the bytes hold them
// (a count of 10^9 allocates 32 GB: found by fuzzing), so the counts are checked here first.
class Wire {
 public:
  Wire(const void* data, size_t size) : p_(static_cast<const uint8_t*>(data)), n_(size) {}
  bool skip(size_t k) {
    if (k > n_ - at_) return ok_ = false;
    at_ += k;
    return true;
  }
  int64_t i32() {
    if (!skip(4)) return -1;
    const uint8_t* q = p_ + at_ - 4;
    return int32_t(uint32_t(q[0]) << 24 | uint32_t(q[1]) << 16 | uint32_t(q[2]) << 8 | q[3]);
  }
  void str() {
    const int64_t len = i32();
    if (len < 1) ok_ = false;
    if (ok_) skip(size_t(len));
  }
  // `count` elements of at least `min_size` bytes each must fit in what is left.
  bool fits(int64_t count, size_t min_size) {
    if (count < 0 || uint64_t(count) * min_size > n_ - at_) ok_ = false;
    return ok_;
  }
  bool ok() const { return ok_; }

 private:
  const uint8_t* p_;
  size_t n_, at_ = 0;
  bool ok_ = true;
};

bool tape_block_wire_ok(const void* data, size_t size) {
  Wire w(data, size);
  w.skip(8);
  w.str();            // run_id
  w.skip(8 + 8 + 8);  // seq, start_sample, sample_rate_hz
  const int64_t nc = w.i32();
  if (!w.fits(nc, 5)) return false;
  for (int64_t c = 0; c < nc && w.ok(); ++c) w.str();
  w.i32();  // n_samples
  const int64_t nv = w.i32();
  return w.fits(nv, 8);
}

// The fields of a status event up to its lines (both forms); false when a count exceeds the bytes.
bool status_common_wire_ok(Wire& w) {
  w.skip(8);
  w.str();
  w.skip(8 + 8 + 8);
  w.str();  // excitation
  w.str();  // state
  w.skip(4 + 4 + 8 + 8 + 4 + 8);
  const int64_t ni = w.i32();
  if (!w.fits(ni, 5 + 8)) return false;
  for (int64_t i = 0; i < ni && w.ok(); ++i) w.str();
  w.skip(size_t(std::max<int64_t>(ni, 0)) * 8);
  w.str();  // message
  w.skip(4);
  const int64_t nl = w.i32();
  if (!w.fits(nl, 8)) return false;
  w.skip(size_t(nl) * 8);  // lines, line_input
  return w.ok();
}

bool status_v1_wire_ok(const void* data, size_t size) {
  Wire w(data, size);
  return status_common_wire_ok(w);
}

}  // namespace

bool status_wire_ok(const void* data, size_t size) {
  Wire w(data, size);
  if (!status_common_wire_ok(w)) return false;
  w.skip(1 + 8);  // has_measurement_chain, its sample_rate_hz
  w.str();        // hold
  w.skip(8);      // converter_delay_s
  const int64_t nr = w.i32();
  return w.fits(nr, 5);
}

tape_block_t to_tape_msg(const Block& b) {
  tape_block_t m = to_msg<tape_block_t>(b);
  m.crc32 = crc_of(m);
  return m;
}
command_block_t to_command_msg(const Block& b) { return to_msg<command_block_t>(b); }
Block from_msg(const tape_block_t& m) {
  Block b = from(m, "tape_block_t");
  if (m.crc32 >= 0) {
    const int64_t crc = crc_of(m);
    if (crc != m.crc32)
      throw CorruptBlock("tape block seq " + std::to_string(m.seq) + " of run " + m.run_id +
                             " failed its checksum (stored " + std::to_string(m.crc32) +
                             ", computed " + std::to_string(crc) + "): the block is corrupt",
                         m.seq);
  }
  return b;
}

Block decode_tape_block(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
  auto refuse = [&] {
    return InputError("channel " + channel + ": message of " + std::to_string(rbuf->data_size) +
                      " bytes is not a fralab.tape_block_t (wrong type or corrupt): check what "
                      "publishes on " +
                      channel);
  };
  if (!tape_block_wire_ok(rbuf->data, rbuf->data_size)) throw refuse();
  tape_block_t m;
  const int n = m.decode(rbuf->data, 0, int(rbuf->data_size));
  if (n >= 0 && uint32_t(n) == rbuf->data_size) return from_msg(m);
  // A tape recorded before checksums.
  tape_block_v1_t v1;
  const int n1 = v1.decode(rbuf->data, 0, int(rbuf->data_size));
  if (n1 >= 0 && uint32_t(n1) == rbuf->data_size) return from(v1, "tape_block_v1_t");
  throw refuse();
}
Block from_msg(const command_block_t& m) { return from(m, "command_block_t"); }

namespace {

measurement_chain_t to_chain_msg(const MeasurementChain& c) {
  const Json j = chain_to_json(c);  // the words of §12, as the JSON files write them
  measurement_chain_t m;
  m.sample_rate_hz = c.sample_rate_hz;
  m.hold = j["hold"];
  m.converter_delay_s = c.converter_delay_s;
  m.n_reheld = int32_t(c.reheld_inputs.size());
  m.reheld_inputs = c.reheld_inputs;
  return m;
}

// Through chain_from_json, so a field travels under the same checks as in run.json.
MeasurementChain from_chain_msg(const measurement_chain_t& m, const std::string& where) {
  return chain_from_json({{"sample_rate_hz", m.sample_rate_hz},
                          {"hold", m.hold},
                          {"converter_delay_s", m.converter_delay_s},
                          {"reheld_inputs", m.reheld_inputs}},
                         {where, "measurement_chain"});
}

// The fields excitation_status_t and excitation_status_v1_t share.
template <class Msg>
StatusEvent from_status(const Msg& m) {
  StatusEvent e;
  e.run_id = m.run_id;
  e.seq = m.seq;
  e.sample = m.sample;
  e.sample_rate_hz = m.sample_rate_hz;
  e.excitation = excitation_from_status_word(m.excitation);
  e.state = run_state_from_string(m.state);
  e.step = m.step;
  e.n_steps = m.n_steps;
  e.frequency_hz = m.frequency_hz;
  e.ref_phase_rad = m.ref_phase_rad;
  e.n_cycles = m.n_cycles;
  e.n_samples = m.n_samples;
  e.inputs = m.inputs;
  e.amplitudes = m.amplitudes;
  e.message = m.message;
  e.period_samples = m.period_samples;
  e.lines.assign(m.lines.begin(), m.lines.end());
  e.line_input.assign(m.line_input.begin(), m.line_input.end());
  return e;
}

std::string status_where(const std::string& run_id, int64_t seq) {
  return "status event seq " + std::to_string(seq) + " of run " + run_id;
}

}  // namespace

excitation_status_t to_status_msg(const StatusEvent& e) {
  excitation_status_t m;
  m.run_id = e.run_id;
  m.seq = e.seq;
  m.sample = e.sample;
  m.sample_rate_hz = e.sample_rate_hz;
  m.excitation = status_word(e.excitation);
  m.state = to_string(e.state);
  m.step = e.step;
  m.n_steps = e.n_steps;
  m.frequency_hz = e.frequency_hz;
  m.ref_phase_rad = e.ref_phase_rad;
  m.n_cycles = e.n_cycles;
  m.n_samples = e.n_samples;
  m.n_inputs = static_cast<int32_t>(e.inputs.size());
  m.inputs = e.inputs;
  m.amplitudes = e.amplitudes;
  m.amplitudes.resize(e.inputs.size(), 0.0);
  m.message = e.message;
  m.period_samples = e.period_samples;
  m.n_lines = int32_t(e.lines.size());
  m.lines.assign(e.lines.begin(), e.lines.end());
  m.line_input.assign(e.line_input.begin(), e.line_input.end());
  m.line_input.resize(e.lines.size(), 0);
  m.has_measurement_chain = e.measurement_chain.has_value();
  m.measurement_chain = to_chain_msg(e.measurement_chain.value_or(MeasurementChain{}));
  return m;
}

StatusEvent from_msg(const excitation_status_t& m) {
  StatusEvent e = from_status(m);
  try {
    if (m.has_measurement_chain)
      e.measurement_chain = from_chain_msg(m.measurement_chain, status_where(m.run_id, m.seq));
  } catch (const InputError& x) {
    e.measurement_chain_error = x.what();
  }
  return e;
}

StatusEvent from_msg(const excitation_status_v1_t& m) {
  StatusEvent e = from_status(m);
  try {
    e.measurement_chain = chain_from_message(m.message, status_where(m.run_id, m.seq));
  } catch (const InputError& x) {
    e.measurement_chain_error = x.what();
  }
  return e;
}

StatusEvent decode_status_event(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
  if (status_wire_ok(rbuf->data, rbuf->data_size)) {
    excitation_status_t m;
    const int n = m.decode(rbuf->data, 0, int(rbuf->data_size));
    if (n >= 0 && uint32_t(n) == rbuf->data_size) return from_msg(m);
  }
  if (status_v1_wire_ok(rbuf->data, rbuf->data_size)) {
    excitation_status_v1_t v1;
    const int n = v1.decode(rbuf->data, 0, int(rbuf->data_size));
    if (n >= 0 && uint32_t(n) == rbuf->data_size) return from_msg(v1);
  }
  throw InputError("channel " + channel + ": message of " + std::to_string(rbuf->data_size) +
                   " bytes is not a fralab.excitation_status_t (wrong type or corrupt): check "
                   "what publishes on " +
                   channel);
}

std::optional<std::string> peek_run_id(const void* data, size_t size) {
  const auto* p = static_cast<const uint8_t*>(data);
  if (size < 12) return std::nullopt;
  const uint32_t n = uint32_t(p[8]) << 24 | uint32_t(p[9]) << 16 | uint32_t(p[10]) << 8 | p[11];
  if (n < 1 || n > size - 12) return std::nullopt;  // n counts the terminating NUL
  return std::string(reinterpret_cast<const char*>(p + 12), n - 1);
}

// frd_point_t and FrdPoint share their field names: one copy serves both directions, so a field
// added to one and not the other fails to compile instead of being dropped.
template <class From, class To>
static void copy_point(const From& a, To& b) {
  b.step = a.step;
  b.w = a.w;
  b.mag = a.mag;
  b.phase_deg = a.phase_deg;
  b.sigma = a.sigma;
  b.coherence = a.coherence;
  b.h2_rel = a.h2_rel;
  b.h3_rel = a.h3_rel;
  b.nl_rel = a.nl_rel;
  b.sigma_noise = a.sigma_noise;
  b.sigma_nl = a.sigma_nl;
  b.realisations = a.realisations;
  b.line_amplitude = a.line_amplitude;
  b.n_cycles = a.n_cycles;
  b.input = a.input;
  b.amplitude = a.amplitude;
  b.valid = a.valid;
  b.note = a.note;
}

frd_t to_frd_msg(const Frd& frd, const std::string& run_id, int64_t seq, bool complete) {
  frd_t m;
  m.run_id = run_id;
  m.seq = seq;
  m.pair = frd.pair;
  m.complete = complete;
  for (const FrdPoint& p : frd.points) copy_point(p, m.points.emplace_back());
  m.n_points = static_cast<int32_t>(m.points.size());
  return m;
}

Frd from_frd_msg(const frd_t& m) {
  if (m.n_points != int32_t(m.points.size()))
    throw InputError("fralab.frd_t " + m.pair + ": n_points " + std::to_string(m.n_points) +
                     " != " + std::to_string(m.points.size()) + " points");
  Frd f;
  f.pair = m.pair;
  for (const frd_point_t& q : m.points) copy_point(q, f.points.emplace_back());
  std::stable_sort(f.points.begin(), f.points.end(),
                   [](const FrdPoint& a, const FrdPoint& b) { return a.w < b.w; });
  return f;
}

tf_t to_tf_msg(const Tf& tf, const std::string& pair, const std::string& run_id, double fit_error,
               const std::string& status) {
  tf_t m;
  m.run_id = run_id;
  m.pair = pair;
  m.gain = tf.gain;
  auto conv = [](const Root& x) {
    root_t q;
    q.kind = x.pair ? "pair" : "real";
    q.real = x.real;
    q.wn = x.wn;
    q.zeta = x.zeta;
    return q;
  };
  for (const Root& z : tf.zeros) m.zeros.push_back(conv(z));
  for (const Root& p : tf.poles) m.poles.push_back(conv(p));
  m.n_zeros = int32_t(m.zeros.size());
  m.n_poles = int32_t(m.poles.size());
  m.delay_s = tf.delay_s;
  m.fit_error = fit_error;
  m.status = status;
  return m;
}

Tf from_tf_msg(const tf_t& m) {
  auto conv = [&](const root_t& q) {
    if (q.kind == "pair") return Root::Pair(q.wn, q.zeta);
    if (q.kind == "real") return Root::Real(q.real);
    throw InputError("fralab.tf_t " + m.pair + ": root kind '" + q.kind +
                     "' is neither 'real' nor 'pair'");
  };
  Tf tf;
  tf.gain = m.gain;
  for (const root_t& z : m.zeros) tf.zeros.push_back(conv(z));
  for (const root_t& p : m.poles) tf.poles.push_back(conv(p));
  tf.delay_s = m.delay_s;
  return tf;
}

}  // namespace fralab
