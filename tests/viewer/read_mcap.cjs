// Reads topics of an MCAP file with Foxglove's own decoders (@mcap/core, @foxglove/rosmsg,
// @foxglove/rosmsg2-serialization) and prints {topic: [{logTime, message}]} as JSON (bigints as strings).
//   node read_mcap.cjs RUN.mcap /tf /tf_static /markers
"use strict";
const fs = require("fs");
const { McapIndexedReader } = require("@mcap/core");
const { parse } = require("@foxglove/rosmsg");
const { MessageReader } = require("@foxglove/rosmsg2-serialization");
const fzstd = require("fzstd");

async function main() {
  const [file, ...topics] = process.argv.slice(2);
  const data = fs.readFileSync(file);
  const readable = {
    size: async () => BigInt(data.length),
    read: async (offset, size) => new Uint8Array(data.buffer, data.byteOffset + Number(offset), Number(size)),
  };
  const reader = await McapIndexedReader.Initialize({
    readable,
    decompressHandlers: { zstd: (buffer, size) => fzstd.decompress(buffer, new Uint8Array(Number(size))) },
  });
  const decoders = new Map();
  for (const [id, channel] of reader.channelsById) {
    const schema = reader.schemasById.get(channel.schemaId);
    const definition = parse(new TextDecoder().decode(schema.data), { ros2: true });
    decoders.set(id, new MessageReader(definition));
  }
  const out = {};
  for await (const message of reader.readMessages({ topics })) {
    const topic = reader.channelsById.get(message.channelId).topic;
    (out[topic] ??= []).push({ logTime: message.logTime, message: decoders.get(message.channelId).readMessage(message.data) });
  }
  process.stdout.write(JSON.stringify(out, (_key, value) => (typeof value === "bigint" ? value.toString() : value)));
}

main().catch((error) => {
  console.error(error);
  process.exit(1);
});
