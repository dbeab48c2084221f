// An MCAP reader the project did not write: @mcap/core (pinned by package-lock.json) in node, with zstd from
// @foxglove/wasm-zstd (what Foxglove Studio uses). For each file, one JSON line on stdout:
//
//   node mcap_read.mjs FILE...
//
// {path, stream: {counts: {topic: n}, metadata: [name], chunks, chunks_without_crc, done, error},
//  indexed: {counts, statistics: {message_count, counts: {topic: n}}, metadata: [name], data_crc, error} | null}
//
// "stream" is McapStreamReader (validateCrcs: every chunk's CRC checked as it is decompressed; a file cut short
// yields the records before the cut, done false); "indexed" is McapIndexedReader, for files with a footer:
// the summary CRC checked on open, every chunk's CRC as its messages are read, and the data section's CRC
// (DataEnd) recomputed here over the bytes before DataEnd, which neither reader checks.
import { crc32 } from "@foxglove/crc";
import * as zstd from "@foxglove/wasm-zstd";
import { McapIndexedReader, McapStreamReader } from "@mcap/core";
import { readFileSync } from "node:fs";

await zstd.isLoaded;
const decompressHandlers = { zstd: (buf, size) => zstd.decompress(buf, Number(size)) };

function stream(data) {
  const out = { counts: {}, metadata: [], chunks: 0, chunks_without_crc: 0, done: false, error: null };
  const topics = new Map();
  const reader = new McapStreamReader({ decompressHandlers, validateCrcs: true, includeChunks: true });
  try {
    reader.append(data);
    for (let rec; (rec = reader.nextRecord());) {
      if (rec.type === "Channel") topics.set(rec.id, rec.topic);
      else if (rec.type === "Message") {
        const t = topics.get(rec.channelId) ?? `#${rec.channelId}`;
        out.counts[t] = (out.counts[t] ?? 0) + 1;
      } else if (rec.type === "Metadata") out.metadata.push(rec.name);
      else if (rec.type === "Chunk") {
        out.chunks++;
        if (rec.uncompressedCrc === 0) out.chunks_without_crc++;
      }
    }
    out.done = reader.done();
  } catch (err) {
    out.error = String(err.message ?? err);
  }
  return out;
}

async function indexed(data) {
  const out = { counts: {}, statistics: null, metadata: [], data_crc: null, error: null };
  const readable = {
    size: async () => BigInt(data.byteLength),
    read: async (offset, size) => data.subarray(Number(offset), Number(offset + size)),
  };
  try {
    const reader = await McapIndexedReader.Initialize({ readable, decompressHandlers });
    for await (const msg of reader.readMessages({ validateCrcs: true })) {
      const t = reader.channelsById.get(msg.channelId)?.topic ?? `#${msg.channelId}`;
      out.counts[t] = (out.counts[t] ?? 0) + 1;
    }
    for await (const m of reader.readMetadata()) out.metadata.push(m.name);
    if (reader.statistics) {
      const counts = {};
      for (const [id, n] of reader.statistics.channelMessageCounts) {
        counts[reader.channelsById.get(id)?.topic ?? `#${id}`] = Number(n);
      }
      out.statistics = { message_count: Number(reader.statistics.messageCount), counts };
    }
    const expected = reader.dataSectionCrc;
    const got = crc32(data.subarray(0, Number(reader.dataEndOffset)));
    out.data_crc = { expected: expected ?? 0, computed: got, ok: expected !== undefined && expected === got };
  } catch (err) {
    out.error = String(err.message ?? err);
  }
  return out;
}

for (const path of process.argv.slice(2)) {
  const data = new Uint8Array(readFileSync(path));
  const s = stream(data);
  process.stdout.write(JSON.stringify({ path, stream: s, indexed: s.done ? await indexed(data) : null }) + "\n");
}
