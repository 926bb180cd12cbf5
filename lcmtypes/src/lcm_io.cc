#include "fralab/lcm_io.h"

#include <sys/select.h>
#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <set>

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

}  // namespace

namespace {

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

}  // namespace

bool status_wire_ok(const void* data, size_t size) {
  Wire w(data, size);
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
  return w.fits(nl, 8);
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
  return m;
}

StatusEvent from_msg(const excitation_status_t& m) {
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

std::string resolve_lcm_url(const std::string& flag) {
  std::string url = flag;
  if (url.empty()) {
    const char* env = std::getenv("LCM_DEFAULT_URL");
    url = env && *env ? env : "udpm://239.255.76.67:7667?ttl=0";
  }
  if (url.rfind("udpm://", 0) != 0) return url;
  // The ttl option, parsed: "?a=1&ttl=0&b=2"; it must be stated.
  long ttl = -2;  // unstated
  const auto q = url.find('?');
  if (q != std::string::npos) {
    for (const std::string& kv : split_list(url.substr(q + 1), '&')) {
      const auto eq = kv.find('=');
      if (kv.substr(0, eq) != "ttl") continue;
      const std::string v = eq == std::string::npos ? "" : kv.substr(eq + 1);
      char* end = nullptr;
      ttl = v.empty() || v.size() > 3 ? -1 : std::strtol(v.c_str(), &end, 10);
      if (ttl < 0 || ttl > 255 || end != v.c_str() + v.size() || (v.size() > 1 && v[0] == '0'))
        throw InputError("LCM URL \"" + url + "\": ttl \"" + v + "\" is not a number 0-255");
    }
  }
  const char* net = std::getenv("FRALAB_NETWORK");
  const bool network = net && std::string(net) == "1";
  if (ttl == -2)
    throw InputError("LCM URL \"" + url +
                     "\" states no ttl: fralab traffic stays on this host unless asked; append "
                     "?ttl=0");
  if (ttl > 0 && !network)
    throw InputError("LCM URL \"" + url + "\" has ttl=" + std::to_string(ttl) +
                     ": fralab traffic stays on this host; reaching other hosts is an explicit "
                     "opt-in: set FRALAB_NETWORK=1");
  return url;
}

std::pair<int, int> ephemeral_port_range() {
  int lo = 32768, hi = 60999;  // Linux's default
  if (std::FILE* f = std::fopen("/proc/sys/net/ipv4/ip_local_port_range", "r")) {
    int a = 0, b = 0;
    if (std::fscanf(f, "%d %d", &a, &b) == 2 && a > 0 && b >= a && b <= 65535) lo = a, hi = b;
    std::fclose(f);
  }
  return {lo, hi};
}

std::string private_lcm_url(uint64_t salt) { return private_lcm_url(salt, ephemeral_port_range()); }

std::string private_lcm_url(uint64_t salt, std::pair<int, int> ephemeral) {
  // Group 239.255.x.y (administratively scoped), an even port P of 10000-65534 with P and P + 1
  // (the control URL's) outside the kernel's ephemeral range, ttl=0. Linux hands a multicast
  // datagram to every socket bound to its port whatever the group, so the port is what separates
  // two runs. Outside the ephemeral range because LCM's send sockets are never bound: each takes an
  // ephemeral port at its first datagram, without SO_REUSEADDR, and a receiver's bind to that port
  // then fails ("bind: Address already in use"; a full test run meets it with tape ports in
  // 20000-59998).
  const auto [lo, hi] = ephemeral;
  const int a_end = std::min(lo - 2, 65534);  // segment A: even P in [10000, a_end], P + 1 < lo
  const int b_begin = std::max(10000, (hi + 2) / 2 * 2);  // segment B: even P >= hi + 1
  const int na = a_end >= 10000 ? (a_end - 10000) / 2 + 1 : 0;
  const int nb = b_begin <= 65534 ? (65534 - b_begin) / 2 + 1 : 0;
  const unsigned x = 1 + (salt % 250), y = 1 + ((salt / 250) % 250);
  unsigned port;
  if (na + nb == 0) {  // the whole range is ephemeral: nothing better than any even port
    port = 10000 + 2 * unsigned((salt / 62500) % 27768);
  } else {
    const int k = int((salt / 62500) % uint64_t(na + nb));
    port = unsigned(k < na ? 10000 + 2 * k : b_begin + 2 * (k - na));
  }
  return "udpm://239.255." + std::to_string(x) + "." + std::to_string(y) + ":" +
         std::to_string(port) + "?ttl=0&recv_buf_size=2097152";
}

void require_lcm(lcm::LCM& lcm, const std::string& what, const std::string& url) {
  if (!lcm.good()) throw InputError("cannot open " + what + " at " + url);
  if (lcm.getFileno() < 0)
    throw InputError("cannot receive on " + what + " at " + url +
                     ": its port is held by another socket (bind failed; see the line above)");
}

LabLcm::LabLcm(const std::string& url, const std::string& ctl_url)
    : data_url(resolve_lcm_url(url)),
      control_url(ctl_url.empty() ? control_url_for(data_url) : resolve_lcm_url(ctl_url)),
      data(data_url),
      control(control_url) {
  require_lcm(data, "LCM", data_url);
  require_lcm(control, "the control LCM URL", control_url);
}

std::string control_url_for(const std::string& url) {
  // udpm://GROUP:PORT?opts -> udpm://GROUP:PORT+1?opts
  auto colon = url.rfind(':');
  auto q = url.find('?', colon == std::string::npos ? 0 : colon);
  if (url.rfind("udpm://", 0) != 0 || colon == std::string::npos || colon < 7) return url;
  std::string port = url.substr(colon + 1, (q == std::string::npos ? url.size() : q) - colon - 1);
  try {
    return url.substr(0, colon + 1) + std::to_string(std::stoi(port) + 1) +
           (q == std::string::npos ? "" : url.substr(q));
  } catch (const std::exception&) {
    return url;
  }
}

std::optional<std::string> peek_run_id(const void* data, size_t size) {
  const auto* p = static_cast<const uint8_t*>(data);
  if (size < 12) return std::nullopt;
  const uint32_t n = uint32_t(p[8]) << 24 | uint32_t(p[9]) << 16 | uint32_t(p[10]) << 8 | p[11];
  if (n < 1 || n > size - 12) return std::nullopt;  // n counts the terminating NUL
  return std::string(reinterpret_cast<const char*>(p + 12), n - 1);
}

void publish_ack(lcm::LCM& control, const std::string& run_id, const std::string& consumer,
                 const std::string& stream, int64_t seq, const char* channel) {
  ack_t a;
  a.run_id = run_id;
  a.consumer = consumer;
  a.stream = stream;
  a.seq = seq;
  control.publish(channel, &a);
}

void publish_flow(lcm::LCM& control, const std::string& run_id, const std::string& kind,
                  const std::string& stream, int64_t from_seq, int64_t to_seq) {
  flow_t f;
  f.run_id = run_id;
  f.kind = kind;
  f.stream = stream;
  f.from_seq = from_seq;
  f.to_seq = to_seq;
  control.publish(kFlowChannel, &f);
}

void handle_either(lcm::LCM& a, lcm::LCM& b, int timeout_ms) {
  if (&a == &b) {  // one instance for data and control (memq:// in tests)
    a.handleTimeout(timeout_ms);
    return;
  }
  fd_set fds;
  FD_ZERO(&fds);
  const int fa = a.getFileno(), fb = b.getFileno();
  FD_SET(fa, &fds);
  FD_SET(fb, &fds);
  timeval tv{timeout_ms / 1000, (timeout_ms % 1000) * 1000};
  if (select(std::max(fa, fb) + 1, &fds, nullptr, nullptr, &tv) <= 0) return;
  if (FD_ISSET(fa, &fds)) a.handle();
  if (FD_ISSET(fb, &fds)) b.handle();
}

namespace {

// The LCM log framing (lcm/eventlog.c), read with explicit bounds so no header can make a reader
// allocate or read what the file does not hold: big-endian int32 sync 0xEDA1DA01, int64 event
// number, int64 timestamp (us), int32 channel length, int32 data length, the channel, the data.
constexpr uint32_t kSync = 0xEDA1DA01u;
constexpr int64_t kHeader = 28;
constexpr int32_t kMaxChannel = 256;            // LCM allows 63
constexpr int64_t kMaxData = int64_t(1) << 30;  // 1 GiB: no fralab message comes near it

uint64_t be(const uint8_t* p, int n) {
  uint64_t v = 0;
  for (int k = 0; k < n; ++k) v = v << 8 | p[k];
  return v;
}

enum class Stop { kEnd, kCut, kCorrupt };

// Whether an event header at `at` (its 28 bytes in h) is possible: the sync word, a channel of
// 1..kMaxChannel bytes, data of 0..kMaxData bytes.
bool possible_header(const uint8_t* h) {
  const int32_t clen = int32_t(be(h + 20, 4)), dlen = int32_t(be(h + 24, 4));
  return uint32_t(be(h, 4)) == kSync && clen > 0 && clen <= kMaxChannel && dlen >= 0 &&
         dlen <= kMaxData;
}

// The first offset in (from, size) where a whole event starts: a possible header whose event ends
// inside the file and whose channel name is printable ASCII (what every LCM channel is). -1 when
// there is none. Reads in chunks; restores nothing (the caller seeks).
int64_t next_event(std::FILE* f, int64_t from, int64_t size) {
  constexpr int64_t kChunk = 1 << 16;
  std::vector<uint8_t> buf;
  for (int64_t pos = from; pos + kHeader <= size; pos += kChunk) {
    const int64_t n = std::min<int64_t>(kChunk + kHeader + kMaxChannel, size - pos);
    buf.resize(size_t(n));
    if (std::fseek(f, long(pos), SEEK_SET) != 0 ||
        std::fread(buf.data(), 1, size_t(n), f) != size_t(n))
      return -1;
    for (int64_t k = 0; k < std::min(kChunk, n) && k + kHeader <= n; ++k) {
      const uint8_t* h = buf.data() + k;
      if (h[0] != 0xED || !possible_header(h)) continue;
      const int32_t clen = int32_t(be(h + 20, 4)), dlen = int32_t(be(h + 24, 4));
      if (pos + k + kHeader + clen + dlen > size) continue;  // would end beyond the file
      if (k + kHeader + clen > n) continue;                  // its name not in this chunk
      bool printable = true;
      for (int32_t c = 0; c < clen && printable; ++c)
        printable = h[kHeader + c] > 0x20 && h[kHeader + c] < 0x7f;
      if (printable) return pos + k;
    }
  }
  return -1;
}

// Reads whole events from byte `from` on; *end: the offset after the last whole event. Returns how
// the reading stopped: the end of the file, a last event cut short (the file ends inside it), or
// bytes that are not an event (*why says which). With `skipped`, bytes that are not an event are
// passed over to the next whole event (next_event), each stretch recorded as [first, end) byte
// offsets, and the reading goes on; without a next whole event the reading stops there (kCorrupt)
// and the stretch is not recorded.
Stop read_events(const std::string& path, int64_t from, int64_t* end, int64_t* n, std::string* why,
                 const std::function<void(const TapeEvent&)>& fn,
                 std::vector<std::pair<int64_t, int64_t>>* skipped = nullptr) {
  if (!std::filesystem::exists(path)) throw InputError(path + ": no such tape file");
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) throw InputError(path + ": cannot open the tape file");
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> closer(f, &std::fclose);
  std::error_code ec;
  const int64_t size = int64_t(std::filesystem::file_size(path, ec));
  if (ec) throw InputError(path + ": cannot read its size");
  *end = from;
  *n = 0;
  if (from > 0 && std::fseek(f, long(from), SEEK_SET) != 0)
    throw InputError(path + ": cannot seek to offset " + std::to_string(from));
  std::vector<uint8_t> buf;
  uint8_t h[kHeader];
  int64_t at = from;
  for (;;) {
    if (at == size) return Stop::kEnd;
    if (size - at < kHeader || std::fread(h, 1, kHeader, f) != size_t(kHeader)) return Stop::kCut;
    const uint32_t sync = uint32_t(be(h, 4));
    const int64_t eventnum = int64_t(be(h + 4, 8)), ts = int64_t(be(h + 12, 8));
    const int32_t clen = int32_t(be(h + 20, 4)), dlen = int32_t(be(h + 24, 4));
    if (!possible_header(h)) {
      if (sync != kSync)
        *why = "no event at byte " + std::to_string(at) + " (sync word " + std::to_string(sync) +
               ", not an LCM log event)";
      else
        *why = "event at byte " + std::to_string(at) + " claims a channel of " +
               std::to_string(clen) + " bytes and data of " + std::to_string(dlen) +
               " bytes (impossible)";
      if (!skipped) return Stop::kCorrupt;
      const int64_t next = next_event(f, at + 1, size);
      if (next < 0 || std::fseek(f, long(next), SEEK_SET) != 0) return Stop::kCorrupt;
      skipped->emplace_back(at, next);
      at = next;
      continue;
    }
    const int64_t body = int64_t(clen) + dlen;
    if (size - at - kHeader < body) return Stop::kCut;  // the file ends inside this event
    buf.resize(size_t(body));
    if (std::fread(buf.data(), 1, size_t(body), f) != size_t(body)) return Stop::kCut;
    const std::string channel(reinterpret_cast<const char*>(buf.data()), size_t(clen));
    TapeEvent te{eventnum, ts, channel, buf.data() + clen, dlen};
    fn(te);
    ++*n;
    at += kHeader + body;
    *end = at;
  }
}

std::string skipped_text(const std::string& path,
                         const std::vector<std::pair<int64_t, int64_t>>& skipped) {
  std::string t;
  for (const auto& [a, b] : skipped)
    t += (t.empty() ? "" : "; ") + path + ": damaged stretch: bytes " + std::to_string(a) + " to " +
         std::to_string(b - 1) + " (" + std::to_string(b - a) +
         " bytes) are not LCM log events; read on from the next whole event at byte " +
         std::to_string(b);
  return t;
}

}  // namespace

int64_t read_tape_file(const std::string& path, const std::function<void(const TapeEvent&)>& fn,
                       std::string* warning, TapeDamage* damage) {
  int64_t end = 0, n = 0;
  std::string why;
  std::vector<std::pair<int64_t, int64_t>> skipped;
  const Stop stop = read_events(path, 0, &end, &n, &why, fn, &skipped);
  if (damage) damage->skipped = skipped;
  std::string w = skipped_text(path, skipped);
  if (stop == Stop::kCorrupt) {
    // Bytes that are not an event up to the end of the file: everything before them was read.
    if (n == 0)
      throw InputError(path + ": corrupt tape: " + std::to_string(n) + " events read, then " + why);
    const int64_t size = int64_t(std::filesystem::file_size(path));
    if (damage) damage->skipped.emplace_back(end, size);
    w += (w.empty() ? "" : "; ") + path + ": corrupt tape: " + std::to_string(n) +
         " events read, then " + why + "; no whole event after it (bytes " + std::to_string(end) +
         " to " + std::to_string(size - 1) + " passed over)";
  }
  if (stop == Stop::kCut) {
    w += (w.empty() ? "" : "; ") + path +
         ": the tape ends inside an event (cut mid-write at byte " +
         std::to_string(std::filesystem::file_size(path)) + "): read its " + std::to_string(n) +
         " whole events, up to byte " + std::to_string(end);
  }
  if (!w.empty()) {
    if (warning)
      *warning = w;
    else
      std::cerr << "fralab: warning: " << w << "\n";
  }
  return n;
}

int64_t follow_tape_file(const std::string& path, int64_t* offset,
                         const std::function<void(const TapeEvent&)>& fn) {
  int64_t end = 0, n = 0;
  std::string why;
  std::vector<std::pair<int64_t, int64_t>> skipped;
  if (read_events(path, *offset, &end, &n, &why, fn, &skipped) == Stop::kCorrupt && n == 0 &&
      *offset == 0)
    throw InputError(path + ": corrupt tape: " + why);
  *offset = end;
  return n;
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

Json tape_summary(const std::string& path) {
  Json j{{"file", path}, {"events", Json::object()}, {"states", Json::object()}};
  std::vector<int64_t> seqs, corrupt;
  std::set<int64_t> seen;
  int64_t copies = 0, aborts = 0;
  std::vector<std::string> channels;
  bool final_block = false;
  int64_t samples = 0;
  double fs = 0;
  std::string warning;
  TapeDamage damage;
  read_tape_file(
      path,
      [&](const TapeEvent& ev) {
        j["events"][ev.channel] = j["events"].value(ev.channel, 0) + 1;
        lcm::ReceiveBuffer rb{const_cast<void*>(ev.data), uint32_t(ev.datalen), 0};
        try {
          if (ev.channel == kTapeChannel) {
            Block b;
            try {
              b = decode_tape_block(&rb, ev.channel);
            } catch (const CorruptBlock& c) {
              corrupt.push_back(c.seq);
              return;
            }
            if (b.seq < 0) {  // an aborted run's last block: actuators to their operating point
              ++aborts;
              return;
            }
            if (!seen.insert(b.seq).second) {  // a retransmitted copy
              ++copies;
              return;
            }
            seqs.push_back(b.seq);
            if (channels.empty()) channels = b.channels;
            final_block |= b.final_block;
            samples += b.n_samples;
            fs = b.sample_rate_hz;
          } else if (ev.channel == kStatusChannel) {
            StatusEvent e = from_msg(decode_checked<excitation_status_t>(&rb, ev.channel));
            j["states"][to_string(e.state)] = j["states"].value(to_string(e.state), 0) + 1;
            if (e.state == RunState::kStart && !j.contains("measurement_chain"))
              if (auto c = chain_from_message(e.message,
                                              path + ": event " + std::to_string(ev.eventnum)))
                j["measurement_chain"] = chain_to_json(*c);
          }
        } catch (const InputError& e) {
          throw InputError(path + ": event " + std::to_string(ev.eventnum) + ": " + e.what());
        }
      },
      &warning, &damage);
  if (!warning.empty()) j["warning"] = warning;
  Json damaged = Json::array();  // the stretches passed over: [first byte, last byte]
  for (const auto& [a, b] : damage.skipped)
    damaged.push_back({{"from_byte", a}, {"to_byte", b - 1}});
  j["damaged"] = damaged;
  std::sort(seqs.begin(), seqs.end());
  Json gaps = Json::array();
  for (size_t i = 1; i < seqs.size(); ++i) {
    for (int64_t q = seqs[i - 1] + 1; q < seqs[i]; ++q) gaps.push_back(q);
  }
  j["channels"] = channels;
  j["tape_blocks"] = seqs.size();
  j["first_seq"] = seqs.empty() ? -1 : seqs.front();
  j["last_seq"] = seqs.empty() ? -1 : seqs.back();
  j["missing_seqs"] = gaps;
  j["corrupt_seqs"] = corrupt;  // blocks whose checksum failed (refused)
  j["retransmitted_copies"] = copies;
  j["abort_blocks"] = aborts;
  j["final_block"] = final_block;
  j["samples"] = samples;
  j["sample_rate_hz"] = fs;
  j["engine_time_s"] = fs > 0 ? samples / fs : 0.0;
  return j;
}

namespace {

// One run's records from a tape file: the first copy of each tape block of the run (seq >= 0,
// below `below`) by seq, and, when `events` is given, every status event of every run in tape
// order (the run is known only once a block names it). *run_id "" takes the first block's run.
std::map<int64_t, Block> collect_run(const std::string& path, std::string* run_id, int64_t below,
                                     std::vector<StatusEvent>* events) {
  std::map<int64_t, Block> got;
  read_tape_file(path, [&](const TapeEvent& ev) {
    lcm::ReceiveBuffer rb{const_cast<void*>(ev.data), uint32_t(ev.datalen), 0};
    try {
      if (ev.channel == kTapeChannel) {
        Block b;
        try {
          b = decode_tape_block(&rb, ev.channel);
        } catch (const CorruptBlock&) {  // failed its checksum: a whole copy may follow, else the
          return;                        // block is named missing (blocks_in_order)
        }
        if (run_id->empty()) *run_id = b.run_id;
        if (b.run_id == *run_id && b.seq >= 0 && b.seq < below && !got.count(b.seq))
          got.emplace(b.seq, std::move(b));
      } else if (events && ev.channel == kStatusChannel) {
        events->push_back(from_msg(decode_checked<excitation_status_t>(&rb, ev.channel)));
      }
    } catch (const InputError& e) {
      throw InputError(path + ": event " + std::to_string(ev.eventnum) + ": " + e.what());
    }
  });
  return got;
}

// Blocks 0 .. count - 1 in seq order; InputError naming the first one missing.
std::vector<Block> blocks_in_order(const std::string& path, const std::string& run_id,
                                   std::map<int64_t, Block>& got, int64_t count) {
  std::vector<Block> out;
  for (int64_t s = 0; s < count; ++s) {
    auto it = got.find(s);
    if (it == got.end())
      throw InputError(path + ": run " + run_id + " lacks tape block seq " + std::to_string(s));
    out.push_back(std::move(it->second));
  }
  return out;
}

}  // namespace

std::vector<Block> read_tape_blocks(const std::string& path, const std::string& run_id,
                                    int64_t below) {
  std::string id = run_id;
  auto got = collect_run(path, &id, below, nullptr);
  return blocks_in_order(path, run_id, got, below);
}

TapeRun read_tape_run(const std::string& path, const std::string& run_id) {
  TapeRun run;
  run.run_id = run_id;
  std::vector<StatusEvent> events;
  auto blocks = collect_run(path, &run.run_id, INT64_MAX, &events);
  if (blocks.empty())
    throw InputError(path + ": no tape blocks" +
                     (run_id.empty() ? std::string() : " of run " + run_id));
  // The run's status events, each seq once (the start and abort events, seq -1, each once).
  std::set<std::pair<int64_t, int>> seen;
  for (auto& e : events)
    if (e.run_id == run.run_id && seen.insert({e.seq, e.seq < 0 ? int(e.state) : 0}).second)
      run.events.push_back(std::move(e));
  run.blocks = blocks_in_order(path, run.run_id, blocks, blocks.rbegin()->first + 1);
  return run;
}

void write_tape_file(const std::string& path, const std::vector<Block>& blocks,
                     const std::vector<StatusEvent>& events) {
  lcm::LogFile log(path, "w");
  if (!log.good()) throw InputError(path + ": cannot be written");
  int64_t eventnum = 0;
  auto put = [&](const char* channel, const auto& msg, double t_s) {
    std::vector<uint8_t> buf(size_t(msg.getEncodedSize()));
    msg.encode(buf.data(), 0, int(buf.size()));
    lcm::LogEvent ev;
    ev.eventnum = eventnum++;
    ev.timestamp = int64_t(std::llround(t_s * 1e6));
    ev.channel = channel;
    ev.datalen = int32_t(buf.size());
    ev.data = buf.data();
    if (log.writeEvent(&ev) != 0) throw InputError(path + ": write failed");
  };
  auto time_of = [](const StatusEvent& e) {
    return e.sample_rate_hz > 0 ? double(e.sample) / e.sample_rate_hz : 0.0;
  };
  size_t next = 0;
  for (const Block& b : blocks) {
    const int64_t last = b.start_sample + b.n_samples - 1;
    while (next < events.size() &&
           ((events[next].seq < 0 && events[next].state == RunState::kStart) ||
            events[next].sample <= last)) {
      put(kStatusChannel, to_status_msg(events[next]), time_of(events[next]));
      ++next;
    }
    put(kTapeChannel, to_tape_msg(b), double(b.start_sample) / b.sample_rate_hz);
  }
  for (; next < events.size(); ++next)
    put(kStatusChannel, to_status_msg(events[next]), time_of(events[next]));
  if (std::fflush(log.getFilePtr()) != 0) throw InputError(path + ": write failed");
}

}  // namespace fralab
