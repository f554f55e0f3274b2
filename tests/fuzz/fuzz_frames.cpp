// The host's frame decoder (noise, truncation, timeouts) and the stream-block assembler.
#include "fuzz.hpp"
#include "link/frame.hpp"
#include "link/stream_block.hpp"

#include <algorithm>
#include <span>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  // First byte: how the bytes arrive (chunk length 1..16) and the rpm window (1..64 samples).
  const std::size_t chunk = (data[0] & 0x0fu) + 1u;
  const int window = ((data[0] >> 4) & 0x0f) * 4 + 1;
  const std::span<const std::uint8_t> bytes(data + 1, size - 1);
  mcg::link::Decoder decoder;
  mcg::link::StreamAssembler assembler(window);
  std::vector<mcg::link::Frame> frames;
  double now_s = 0.0;
  for (std::size_t at = 0; at < bytes.size(); at += chunk) {
    const auto piece = bytes.subspan(at, std::min(chunk, bytes.size() - at));
    decoder.feed(piece, now_s, frames);
    // A byte of the piece picks a pause: most pieces follow at once, some after a silence.
    now_s += (piece[0] & 0x80u) != 0 ? 0.5 : 0.0005;
    decoder.poll(now_s, frames);
  }
  decoder.poll(now_s + 10.0, frames);
  if (decoder.pending()) mcg::fuzz::finding("a partial frame survived the final timeout");
  for (const auto& f : frames) {
    if (f.payload.size() > MCG_MAX_PAYLOAD) mcg::fuzz::finding("a frame longer than MCG_MAX_PAYLOAD");
    if (f.cmd == MCG_MSG_STREAM) assembler.push(f.payload, 0.064);
  }
  // The raw bytes as payloads too, so the assembler sees malformed and odd-sized blocks.
  for (std::size_t at = 0; at < bytes.size(); at += 64) {
    assembler.push(bytes.subspan(at, std::min<std::size_t>(64, bytes.size() - at)), (bytes[at] & 1u) ? 0.064 : 30.0);
  }
  (void)assembler.lost_samples();
  return 0;
}
