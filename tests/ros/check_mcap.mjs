// Reads an MCAP file with the official reader (@mcap/core's McapStreamReader, CRCs validated,
// zstd and lz4 chunks decompressed by Foxglove's wasm codecs) and prints what it holds as JSON:
// per topic its schema, encodings and message count; the time span; and whether every JSON
// message parses. Exit 1 when the reader rejects the file.
//   node check_mcap.mjs FILE
import { readFileSync } from "node:fs";
import { createRequire } from "node:module";

const require = createRequire(import.meta.url);
const { McapStreamReader } = require("./node/node_modules/@mcap/core");
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
  let start = null, end = null, jsonErrors = 0, statistics = null, footer = false;
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
      }
    } else if (r.type === "Statistics") statistics = { messages: Number(r.messageCount), channels: r.channelCount };
    else if (r.type === "Footer") footer = true;
  }
  if (!reader.done()) throw new Error(`${reader.bytesRemaining()} bytes left unread`);
  console.log(JSON.stringify({ topics, start_ns: String(start), end_ns: String(end), json_errors: jsonErrors, statistics, footer }));
} catch (e) {
  console.error(`check_mcap: ${process.argv[2]}: ${e.message}`);
  process.exit(1);
}
