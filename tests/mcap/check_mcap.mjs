// SPDX-License-Identifier: Apache-2.0
// Reads an MCAP file with an independent implementation (@mcap/core, the reference TypeScript
// library; zstd by fzstd, lz4 by lz4js) and prints what it found as JSON:
//   node check_mcap.mjs <file.mcap> [--allow-truncated]
// Stream pass: every record in file order, every chunk's CRC validated. Indexed pass (when the
// file has a summary): every message through the chunk and message indexes. Exit 1 with the error
// in "errors" if either pass fails, if they disagree, or if the file is cut (unless
// --allow-truncated, for a recorder killed on purpose).
import { readFileSync } from "node:fs";
import { McapIndexedReader, McapStreamReader } from "@mcap/core";
import { decompress as zstdDecompress } from "fzstd";
import lz4 from "lz4js";

const args = process.argv.slice(2);
const file = args.find((a) => !a.startsWith("--"));
const allowTruncated = args.includes("--allow-truncated");
if (!file) {
  console.error("usage: node check_mcap.mjs <file.mcap> [--allow-truncated]");
  process.exit(2);
}

const decompressHandlers = {
  zstd: (buffer, decompressedSize) => zstdDecompress(buffer, new Uint8Array(Number(decompressedSize))),
  lz4: (buffer, decompressedSize) => Uint8Array.from(lz4.decompress(buffer, Number(decompressedSize))),
};

const bytes = new Uint8Array(readFileSync(file));
const result = {
  file,
  bytes: bytes.length,
  profile: null,
  library: null,
  schemas: [],
  topics: {},
  messages: 0,
  chunks: 0,
  complete: false,
  summary: false,
  indexed_messages: null,
  statistics_messages: null,
  errors: [],
};

function streamPass() {
  const reader = new McapStreamReader({ includeChunks: true, decompressHandlers, validateCrcs: true });
  reader.append(bytes);
  const channels = new Map();
  for (let record; (record = reader.nextRecord()); ) {
    switch (record.type) {
      case "Header":
        result.profile = record.profile;
        result.library = record.library;
        break;
      case "Schema":
        if (!result.schemas.some((s) => s.id === record.id))
          result.schemas.push({ id: record.id, name: record.name, encoding: record.encoding, bytes: record.data.length });
        break;
      case "Channel":
        channels.set(record.id, record);
        break;
      case "Chunk":
        result.chunks += 1;
        break;
      case "Message": {
        const channel = channels.get(record.channelId);
        if (!channel) throw new Error(`message of unknown channel ${record.channelId}`);
        result.topics[channel.topic] = (result.topics[channel.topic] ?? 0) + 1;
        result.messages += 1;
        break;
      }
      case "Footer":
        result.summary = record.summaryStart !== 0n;
        break;
      default:
        break;
    }
  }
  result.complete = reader.done();
}

async function indexedPass() {
  const readable = {
    size: async () => BigInt(bytes.length),
    read: async (offset, length) => bytes.subarray(Number(offset), Number(offset + length)),
  };
  const reader = await McapIndexedReader.Initialize({ readable, decompressHandlers });
  result.statistics_messages = reader.statistics ? Number(reader.statistics.messageCount) : null;
  let count = 0;
  for await (const message of reader.readMessages({ validateCrcs: true })) {
    if (!reader.channelsById.has(message.channelId)) throw new Error(`indexed message of unknown channel`);
    count += 1;
  }
  result.indexed_messages = count;
}

try {
  streamPass();
  if (!result.complete && !allowTruncated) result.errors.push("the file ends before its footer (truncated)");
  if (result.complete) {
    await indexedPass();
    if (result.indexed_messages !== result.messages)
      result.errors.push(`indexed read found ${result.indexed_messages} messages, stream read ${result.messages}`);
    if (result.statistics_messages !== null && result.statistics_messages !== result.messages)
      result.errors.push(`statistics say ${result.statistics_messages} messages, stream read ${result.messages}`);
  }
} catch (error) {
  result.errors.push(String(error?.message ?? error));
}
console.log(JSON.stringify(result));
process.exit(result.errors.length === 0 ? 0 : 1);
