// SPDX-License-Identifier: Apache-2.0
// Decodes every message of every channel of a ros2-profile MCAP file as Foxglove does
// (@foxglove/ros2idl-parser for the ros2idl schema, @foxglove/rosmsg2-serialization's MessageReader
// for the CDR, @mcap/core to read the file) and prints what it found as JSON:
//   node decode_ros2.mjs <file.mcap> [--dump-dir DIR]
// Per channel: the schema, the type the parser takes as the message's own (the reader decodes with
// the first struct it finds), how many messages decoded, how many left bytes unread, and the first
// errors. With --dump-dir, DIR/<topic with '/' as '_'>.jsonl holds every decoded message (64-bit
// integers as decimal strings). Exit 1 if a channel's schema or any of its messages does not decode
// as the schema's named type.
import { mkdirSync, readFileSync, writeFileSync } from "node:fs";
import { join } from "node:path";
import { McapIndexedReader } from "@mcap/core";
import { parseRos2idl } from "@foxglove/ros2idl-parser";
import { MessageReader } from "@foxglove/rosmsg2-serialization";
import { decompress as zstdDecompress } from "fzstd";
import lz4 from "lz4js";

const args = process.argv.slice(2);
const file = args.find((a, i) => !a.startsWith("--") && args[i - 1] !== "--dump-dir");
const dumpIndex = args.indexOf("--dump-dir");
const dumpDir = dumpIndex >= 0 ? args[dumpIndex + 1] : null;
if (!file) {
  console.error("usage: node decode_ros2.mjs <file.mcap> [--dump-dir DIR]");
  process.exit(2);
}

const decompressHandlers = {
  zstd: (buffer, size) => zstdDecompress(buffer, new Uint8Array(Number(size))),
  lz4: (buffer, size) => Uint8Array.from(lz4.decompress(buffer, Number(size))),
};

// JSON for a decoded message: bigints as strings, typed arrays as arrays.
const toJson = (value) =>
  JSON.stringify(value, (_key, v) => {
    if (typeof v === "bigint") return v.toString();
    if (ArrayBuffer.isView(v)) return Array.from(v, (x) => (typeof x === "bigint" ? x.toString() : x));
    return v;
  });

// The channel's decoder, built as Foxglove's parseChannel builds it for cdr + ros2idl.
function channelDecoder(channel, schema) {
  const entry = { topic: channel.topic, schema: schema?.name ?? null, encoding: schema?.encoding ?? null };
  entry.root = null;
  entry.messages = 0;
  entry.decoded = 0;
  entry.trailing = 0;
  entry.errors = [];
  if (channel.messageEncoding !== "cdr" || schema?.encoding !== "ros2idl") {
    entry.errors.push(`not cdr + ros2idl: ${channel.messageEncoding} + ${schema?.encoding}`);
    return { entry, reader: null };
  }
  try {
    const definitions = parseRos2idl(new TextDecoder().decode(schema.data));
    // MessageReader's root: the first definition that is not a module of constants only.
    const root = definitions.find((d) => !(d.definitions.length > 0 && d.definitions.every((f) => f.isConstant)));
    entry.root = root?.name ?? null;
    if (entry.root !== schema.name) entry.errors.push(`schema ${schema.name} is read as ${entry.root}`);
    return { entry, reader: new MessageReader(definitions) };
  } catch (error) {
    entry.errors.push(`schema: ${String(error?.message ?? error)}`);
    return { entry, reader: null };
  }
}

async function main() {
  const bytes = new Uint8Array(readFileSync(file));
  const readable = {
    size: async () => BigInt(bytes.length),
    read: async (offset, length) => bytes.subarray(Number(offset), Number(offset + length)),
  };
  const mcap = await McapIndexedReader.Initialize({ readable, decompressHandlers });
  const decoders = new Map();
  for (const [id, channel] of mcap.channelsById) decoders.set(id, channelDecoder(channel, mcap.schemasById.get(channel.schemaId)));
  const dumps = new Map();
  for await (const message of mcap.readMessages()) {
    const { entry, reader } = decoders.get(message.channelId);
    entry.messages += 1;
    if (!reader) continue;
    try {
      const decoded = reader.readMessage(message.data);
      entry.decoded += 1;
      // CDR payloads may end in up to 3 bytes of alignment padding; more is a misread.
      if (message.data.byteLength - reader.lastReadByteLength() > 3) entry.trailing += 1;
      if (dumpDir) {
        if (!dumps.has(entry.topic)) dumps.set(entry.topic, []);
        dumps.get(entry.topic).push(toJson(decoded));
      }
    } catch (error) {
      if (entry.errors.length < 3) entry.errors.push(`message ${message.sequence}: ${String(error?.message ?? error)}`);
    }
  }
  const channels = [...decoders.values()].map(({ entry }) => entry);
  for (const entry of channels) {
    if (entry.trailing > 0) entry.errors.push(`${entry.trailing} messages decoded with bytes left over`);
    if (entry.decoded !== entry.messages) entry.errors.push(`${entry.messages - entry.decoded} messages did not decode`);
  }
  if (dumpDir) {
    mkdirSync(dumpDir, { recursive: true });
    for (const [topic, lines] of dumps) writeFileSync(join(dumpDir, `${topic.replaceAll("/", "_")}.jsonl`), lines.join("\n") + "\n");
  }
  const ok = channels.length > 0 && channels.every((c) => c.errors.length === 0);
  console.log(JSON.stringify({ file, ok, channels }));
  return ok ? 0 : 1;
}

main().then(
  (code) => process.exit(code),
  (error) => {
    console.log(JSON.stringify({ file, ok: false, error: String(error?.message ?? error) }));
    process.exit(1);
  },
);
