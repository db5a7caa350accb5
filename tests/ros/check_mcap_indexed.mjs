// Reads an MCAP file through its index with the official reader (@mcap/core's McapIndexedReader:
// footer, summary and its CRC, chunk indexes, message indexes, chunk CRCs; zstd by Foxglove's wasm
// codec), as a viewer seeking in it does, and prints as JSON: the chunks and their compression,
// every topic's message count read through the index, and for one second starting at a time drawn from SEED the number of messages and the
// milliseconds from opening the file to the last of them (`window`; WINDOWS such seconds in
// `windows`). Exit 1 when the reader rejects it.
//   node check_mcap_indexed.mjs FILE [SEED [WINDOWS]]
import { open } from "node:fs/promises";
import { createRequire } from "node:module";

const require = createRequire(import.meta.url);
const { McapIndexedReader } = require("./node/node_modules/@mcap/core");
const zstd = require("./node/node_modules/@foxglove/wasm-zstd");

await zstd.isLoaded;
const decompressHandlers = { zstd: (data, size) => zstd.decompress(data, Number(size)) };
const file = process.argv[2];
const seed = Number(process.argv[3] ?? 1);
const count = Number(process.argv[4] ?? 1);

async function openReader() {
  const handle = await open(file, "r");
  const readable = {
    size: async () => BigInt((await handle.stat()).size),
    read: async (offset, size) => {
      const buffer = new Uint8Array(Number(size));
      await handle.read(buffer, 0, Number(size), Number(offset));
      return buffer;
    },
  };
  return { handle, reader: await McapIndexedReader.Initialize({ readable, decompressHandlers }) };
}

try {
  const { handle, reader } = await openReader();
  const topics = {};
  let messages = 0;
  for await (const m of reader.readMessages({ validateCrcs: true })) {
    const topic = reader.channelsById.get(m.channelId).topic;
    topics[topic] = (topics[topic] ?? 0) + 1;
    ++messages;
  }
  const compressions = [...new Set(reader.chunkIndexes.map((c) => c.compression))];
  const start = reader.statistics.messageStartTime, end = reader.statistics.messageEndTime;
  await handle.close();
  // WINDOWS seconds, each from a time drawn from the seed (Park-Miller's generator, warmed up so
  // that small seeds spread over the span), each through a freshly opened reader.
  const span = end - start > 1000000000n ? end - start - 1000000000n : 0n;
  let x = BigInt(seed % 2147483646) + 1n;
  const next = () => { x = (x * 48271n) % 2147483647n; return Number(x) / 2147483647; };
  for (let k = 0; k < 4; ++k) next();
  const windows = [];
  for (let w = 0; w < count; ++w) {
    const from = start + BigInt(Math.floor(next() * Number(span))), to = from + 1000000000n;
    const t0 = performance.now();
    const second = await openReader();
    let inWindow = 0;
    for await (const m of second.reader.readMessages({ startTime: from, endTime: to, validateCrcs: true })) {
      if (m.logTime < from || m.logTime > to) throw new Error("a message outside the window");
      ++inWindow;
    }
    windows.push({ start_ns: String(from), messages: inWindow, ms: performance.now() - t0 });
    await second.handle.close();
  }
  const window = windows[0];
  console.log(JSON.stringify({
    chunks: reader.chunkIndexes.length, compressions, topics, messages,
    statistics_messages: Number(reader.statistics.messageCount),
    window, windows,
  }));
} catch (e) {
  console.error(`check_mcap_indexed: ${file}: ${e.message}`);
  process.exit(1);
}
