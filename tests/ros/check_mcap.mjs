// Reads an MCAP file with the official reader (@mcap/core's McapStreamReader, CRCs validated,
// zstd and lz4 chunks decompressed by Foxglove's wasm codecs) and prints what it holds as JSON:
// per topic its schema, encodings and message count; the time span; whether every JSON message
// parses; and every CDR message decoded by the official deserializer
// (@foxglove/rosmsg2-serialization over the file's ros2msg schema, parsed by @foxglove/rosmsg):
// the failures counted, each topic's first and last messages kept (image data as its length and first
// bytes). Exit 1 when the reader rejects the file.
//   node check_mcap.mjs FILE
import { readFileSync } from "node:fs";
import { createRequire } from "node:module";

const require = createRequire(import.meta.url);
const { McapStreamReader } = require("./node/node_modules/@mcap/core");
const { MessageReader } = require("./node/node_modules/@foxglove/rosmsg2-serialization");
const { parse } = require("./node/node_modules/@foxglove/rosmsg");
const zstd = require("./node/node_modules/@foxglove/wasm-zstd");
const lz4 = require("./node/node_modules/@foxglove/wasm-lz4");

await zstd.isLoaded;
await lz4.isLoaded;
const reader = new McapStreamReader({
  validateCrcs: true,
  decompressHandlers: { zstd: (data, size) => zstd.decompress(data, Number(size)), lz4: (data, size) => lz4(data, Number(size)) },
});
try {
  reader.append(new Uint8Array(readFileSync(process.argv[2])));
  const schemas = new Map(), channels = new Map(), topics = {};
  let start = null, end = null, jsonErrors = 0, cdrErrors = 0, statistics = null, footer = false;
  const readers = new Map(), first = {}, last = {};
  for (let r; (r = reader.nextRecord()); ) {
    if (r.type === "Schema") schemas.set(r.id, r);
    else if (r.type === "Channel") {
      channels.set(r.id, r);
      const s = schemas.get(r.schemaId);
      topics[r.topic] ??= { schema: s ? s.name : "", schema_encoding: s ? s.encoding : "", message_encoding: r.messageEncoding, count: 0 };
    } else if (r.type === "Message") {
      const c = channels.get(r.channelId);
      topics[c.topic].count += 1;
      start = start === null || r.logTime < start ? r.logTime : start;
      end = end === null || r.logTime > end ? r.logTime : end;
      if (c.messageEncoding === "json") {
        try { JSON.parse(new TextDecoder().decode(r.data)); } catch { jsonErrors += 1; }
      } else if (c.messageEncoding === "cdr") {
        try {
          if (!readers.has(c.schemaId)) {
            const s = schemas.get(c.schemaId);
            if (s.encoding !== "ros2msg") throw new Error(`schema encoding ${s.encoding}`);
            readers.set(c.schemaId, new MessageReader(parse(new TextDecoder().decode(s.data), { ros2: true })));
          }
          const m = readers.get(c.schemaId).readMessage(r.data);
          if (m.data instanceof Uint8Array) m.data = { length: m.data.length, head: Array.from(m.data.slice(0, 8)) };
          first[c.topic] ??= m;
          last[c.topic] = m;
        } catch (e) { cdrErrors += 1; }
      }
    } else if (r.type === "Statistics") statistics = { messages: Number(r.messageCount), channels: r.channelCount };
    else if (r.type === "Footer") footer = true;
  }
  if (!reader.done()) throw new Error(`${reader.bytesRemaining()} bytes left unread`);
  console.log(JSON.stringify({ topics, start_ns: String(start), end_ns: String(end), json_errors: jsonErrors,
    cdr_errors: cdrErrors, first, last, statistics, footer }, (k, v) => (typeof v === "bigint" ? String(v) : v)));
} catch (e) {
  console.error(`check_mcap: ${process.argv[2]}: ${e.message}`);
  process.exit(1);
}
