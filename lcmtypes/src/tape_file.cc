#include "fralab/lcm/tape_file.h"

#include <algorithm>
#include <cstdio>
#include <iostream>
#include <map>
#include <set>

#include "fralab/core/measurement_chain.h"
#include "fralab/core/text.h"
#include "fralab/lcm/channels.h"
#include "fralab/lcm/codec.h"

namespace fralab {

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
            StatusEvent e = decode_status_event(&rb, ev.channel);
            j["states"][to_string(e.state)] = j["states"].value(to_string(e.state), 0) + 1;
            if (e.state == RunState::kStart && !j.contains("measurement_chain") &&
                e.measurement_chain)
              j["measurement_chain"] = chain_to_json(*e.measurement_chain);
            if (!e.measurement_chain_error.empty())
              j["measurement_chain_error"] = path + ": event " + std::to_string(ev.eventnum) +
                                             ": " + e.measurement_chain_error;
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
        events->push_back(decode_status_event(&rb, ev.channel));
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
