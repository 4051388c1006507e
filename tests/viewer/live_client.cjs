// Watches a live fsr flight with Foxglove's own WebSocket client (@foxglove/ws-protocol over `ws`) and decoders
// (@foxglove/rosmsg, @foxglove/rosmsg2-serialization), and prints what it saw as JSON (bigints as strings):
//   {advertised: [{topic, schemaName, encoding, schemaEncoding}], messages: {topic: [{arrival, logTime, message}]}}
// arrival: ms on this process's monotonic clock; finalArrival: that of the first final sim_status (state finished,
// diverged or stopped). Ends when the server closes the connection (the flight is over), or at --timeout.
//   node live_client.cjs ws://127.0.0.1:8765 --subscribe /odom,/tf,/markers,/sim_status
//        [--late /tf_static,/markers --late-after 1.0]   subscribe to these once an /odom stamped >= 1.0 s is in
//        [--raw /odom]                                    also keep these topics' CDR bytes (base64, as `raw`)
//        [--stop-reading]                                 subscribe, then read nothing after the first message
//        [--timeout 60]                                   seconds
"use strict";
const { FoxgloveClient } = require("@foxglove/ws-protocol");
const { parse } = require("@foxglove/rosmsg");
const { MessageReader } = require("@foxglove/rosmsg2-serialization");
const WebSocket = require("ws");

const SUBPROTOCOL = "foxglove.sdk.v1"; // what the Foxglove SDK's server speaks (the v1 protocol under a new name)
const FINAL_STATES = new Set(["finished", "diverged", "stopped"]);

function options(argv) {
  const found = { url: argv[0], subscribe: [], late: [], lateAfter: 0, raw: [], stopReading: false, timeout: 60 };
  for (let i = 1; i < argv.length; i++) {
    const name = argv[i];
    if (name === "--subscribe") found.subscribe = argv[++i].split(",");
    else if (name === "--late") found.late = argv[++i].split(",");
    else if (name === "--late-after") found.lateAfter = Number(argv[++i]);
    else if (name === "--raw") found.raw = argv[++i].split(",");
    else if (name === "--stop-reading") found.stopReading = true;
    else if (name === "--timeout") found.timeout = Number(argv[++i]);
    else throw new Error(`unknown option ${name}`);
  }
  return found;
}

function stampSeconds(message) {
  const stamp = message.header.stamp;
  return stamp.sec + stamp.nanosec * 1e-9;
}

function main() {
  const opts = options(process.argv.slice(2));
  const out = { advertised: [], messages: {}, finalArrival: null };
  const channels = new Map(); // topic -> channel
  const bySubscription = new Map(); // subscription id -> {topic, reader}
  let client;
  let finished = false;
  let lateDone = opts.late.length === 0;

  function finish(code) {
    if (finished) return;
    finished = true;
    const text = JSON.stringify(out, (_key, value) => (typeof value === "bigint" ? value.toString() : value));
    process.stdout.write(text, () => process.exit(code)); // a pipe is written asynchronously: exit once it is
  }
  setTimeout(() => finish(0), opts.timeout * 1000);

  function subscribe(topic) {
    const channel = channels.get(topic);
    if (channel === undefined) return false;
    const definition = parse(channel.schema, { ros2: true });
    bySubscription.set(client.subscribe(channel.id), { topic, reader: new MessageReader(definition) });
    return true;
  }

  function connect() {
    const ws = new WebSocket(opts.url, [SUBPROTOCOL]);
    client = new FoxgloveClient({ ws });
    let wanted = new Set(opts.subscribe);
    ws.on("error", () => {}); // a refused connection: retried below
    client.on("close", () => {
      if (channels.size === 0 && !finished) setTimeout(connect, 100); // the server was not up yet
      else finish(0);
    });
    client.on("advertise", (advertised) => {
      for (const channel of advertised) {
        channels.set(channel.topic, channel);
        out.advertised.push({ topic: channel.topic, schemaName: channel.schemaName, encoding: channel.encoding,
                              schemaEncoding: channel.schemaEncoding });
        if (wanted.has(channel.topic) && subscribe(channel.topic)) wanted.delete(channel.topic);
      }
    });
    client.on("message", ({ subscriptionId, timestamp, data }) => {
      if (opts.stopReading) {
        ws._socket.pause(); // subscribed: read nothing more, the server's queue for this client fills up
        return;
      }
      const arrival = performance.now();
      const entry = bySubscription.get(subscriptionId);
      if (entry === undefined) return;
      const message = entry.reader.readMessage(data);
      const received = { arrival, logTime: timestamp, message };
      if (opts.raw.includes(entry.topic)) {
        received.raw = Buffer.from(data.buffer, data.byteOffset, data.byteLength).toString("base64");
      }
      (out.messages[entry.topic] ??= []).push(received);
      if (!lateDone && entry.topic === "/odom" && stampSeconds(message) >= opts.lateAfter) {
        lateDone = true;
        for (const topic of opts.late) subscribe(topic);
      }
      if (out.finalArrival === null && entry.topic.endsWith("/sim_status") &&
          FINAL_STATES.has(JSON.parse(message.data).state)) {
        out.finalArrival = arrival;
      }
    });
  }
  connect();
}

main();
