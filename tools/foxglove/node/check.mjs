// Checks what tca hands to Foxglove with Foxglove's own packages:
//
//   node check.mjs mcap FILE.mcap
//       reads the file with the official MCAP reader (@mcap/core), decodes every
//       protobuf message through the schema the file carries, and validates it (and every
//       JSON message) against its JSON schema: Foxglove's published one (@foxglove/schemas)
//       for the well-known topics, the file's own for the rest;
//   node check.mjs live ws://HOST:PORT SECONDS TOPIC...
//       connects with the Foxglove WebSocket client (@foxglove/ws-protocol), prints `open`
//       once connected, subscribes to every channel as it is advertised, decodes and
//       validates what arrives the same way, and ends as soon as every TOPIC named has
//       sent a valid message; fails if that takes more than SECONDS.
//
// Prints one JSON line of counts per topic; exits 1 on the first problem, saying what.

import { readFileSync } from "node:fs";
import { McapStreamReader } from "@mcap/core";
import wsProtocol from "@foxglove/ws-protocol";
import foxgloveSchemas from "@foxglove/schemas/jsonschema.js";
import Ajv2020 from "ajv/dist/2020.js";
import protobuf from "protobufjs";
import descriptor from "protobufjs/ext/descriptor/index.js";
import WebSocket from "ws";

const { FoxgloveClient } = wsProtocol;
const ajv = new Ajv2020({ strict: false, allErrors: false });
const validators = new Map();

function fail(message) {
  console.error(`check: ${message}`);
  process.exit(1);
}

// A protobuf schema (a FileDescriptorSet) as a decoder to plain objects.
function protobufDecoder(name, data) {
  const set = descriptor.FileDescriptorSet.decode(data);
  const root = protobuf.Root.fromDescriptor(set);
  const type = root.lookupType(name);
  return (bytes) => {
    const message = type.decode(bytes);
    withDefaults(type, message);
    return type.toObject(message, { longs: Number, enums: Number, bytes: String, defaults: true });
  };
}

// Unset message fields as their default messages, which is what they mean in protobuf (a
// zero lifetime, a zero timestamp) and what the JSON form spells out.
function withDefaults(type, message) {
  for (const field of type.fieldsArray) {
    field.resolve();
    const sub = field.resolvedType;
    if (!(sub instanceof protobuf.Type)) continue;
    if (field.repeated) {
      for (const m of message[field.name] ?? []) withDefaults(sub, m);
    } else {
      if (message[field.name] == null) message[field.name] = sub.create();
      withDefaults(sub, message[field.name]);
    }
  }
}

// protobufjs's field names and well-known types, as Foxglove's JSON schemas spell them.
function toFoxgloveJson(value) {
  if (Array.isArray(value)) return value.map(toFoxgloveJson);
  if (value && typeof value === "object") {
    const keys = Object.keys(value);
    if (keys.length === 2 && "seconds" in value && "nanos" in value) {
      return { sec: Number(value.seconds), nsec: Number(value.nanos) };
    }
    const out = {};
    for (const k of keys) {
      // An unset message field (null here) is left out, as protobuf's JSON mapping does.
      if (value[k] === null) continue;
      const snake = k.replace(/[A-Z]/g, (c) => `_${c.toLowerCase()}`);
      out[snake] = toFoxgloveJson(value[k]);
    }
    return out;
  }
  return value;
}

function validatorFor(key, schema) {
  let v = validators.get(key);
  if (!v) {
    v = ajv.compile(schema);
    validators.set(key, v);
  }
  return v;
}

// The decode-and-validate function of one channel.
function checkerFor(topic, messageEncoding, schemaName, schemaEncoding, schemaData) {
  if (messageEncoding === "protobuf") {
    if (schemaEncoding !== "protobuf") fail(`${topic}: protobuf messages with a ${schemaEncoding} schema`);
    const short = schemaName.replace(/^foxglove\./, "");
    const published = foxgloveSchemas[short];
    if (!published) fail(`${topic}: ${schemaName} is not one of Foxglove's published schemas`);
    const decode = protobufDecoder(schemaName, schemaData);
    const validate = validatorFor(schemaName, published);
    return (bytes) => {
      const json = toFoxgloveJson(decode(bytes));
      if (!validate(json)) {
        fail(`${topic} (${schemaName}): ${ajv.errorsText(validate.errors)} in ${JSON.stringify(json).slice(0, 300)}`);
      }
      return json;
    };
  }
  if (messageEncoding === "json") {
    if (schemaEncoding !== "jsonschema") fail(`${topic}: JSON messages with a ${schemaEncoding} schema`);
    const text = new TextDecoder().decode(schemaData);
    let schema;
    try {
      schema = JSON.parse(text);
    } catch (e) {
      fail(`${topic}: its JSON schema does not parse: ${e}`);
    }
    const validate = validatorFor(`${topic} ${text}`, schema);
    return (bytes) => {
      const json = JSON.parse(new TextDecoder().decode(bytes));
      if (!validate(json)) {
        fail(`${topic}: ${ajv.errorsText(validate.errors)} in ${JSON.stringify(json).slice(0, 300)}`);
      }
      return json;
    };
  }
  fail(`${topic}: message encoding ${messageEncoding} is neither protobuf nor json`);
}

function checkMcap(path) {
  const reader = new McapStreamReader({ validateCrcs: true });
  reader.append(readFileSync(path));
  const schemas = new Map();
  const channels = new Map();
  const counts = {};
  let total = 0;
  for (let record; (record = reader.nextRecord()); ) {
    if (record.type === "Schema") schemas.set(record.id, record);
    if (record.type === "Channel") {
      const s = schemas.get(record.schemaId);
      if (!s) fail(`channel ${record.topic} names schema ${record.schemaId}, which the file does not hold`);
      channels.set(record.id, {
        topic: record.topic,
        check: checkerFor(record.topic, record.messageEncoding, s.name, s.encoding, s.data),
      });
    }
    if (record.type === "Message") {
      const c = channels.get(record.channelId);
      if (!c) fail(`a message on channel ${record.channelId}, which the file never declared`);
      c.check(record.data);
      counts[c.topic] = (counts[c.topic] ?? 0) + 1;
      total += 1;
    }
  }
  if (!reader.done()) fail("the file ends part-way through a record");
  console.log(JSON.stringify({ messages: total, topics: counts }));
}

async function checkLive(url, seconds, wanted) {
  const ws = new WebSocket(url, ["foxglove.sdk.v1"]);
  const client = new FoxgloveClient({ ws });
  const channels = new Map();
  const counts = {};
  client.on("error", (e) => fail(`the WebSocket failed: ${e?.message ?? e}`));
  client.on("open", () => console.log("open"));
  client.on("close", () =>
    fail(`the server closed the connection; received ${JSON.stringify({ topics: counts })}`),
  );
  const finish = () => {
    console.log(JSON.stringify({ channels: channels.size, topics: counts }));
    process.exit(0);
  };
  client.on("advertise", (list) => {
    for (const ch of list) {
      const data =
        ch.schemaEncoding === "protobuf"
          ? Buffer.from(ch.schema, "base64")
          : new TextEncoder().encode(ch.schema);
      channels.set(ch.id, {
        topic: ch.topic,
        check: checkerFor(ch.topic, ch.encoding, ch.schemaName, ch.schemaEncoding ?? "jsonschema", data),
      });
      subscribe(ch.id);
    }
  });
  // The SDK's server records a channel for a client just after advertising it, so a
  // subscription sent back at once can find it unknown: subscribe a moment later, and again
  // if the server says it did not know the channel.
  function subscribe(id) {
    setTimeout(() => {
      const c = channels.get(id);
      if (c) c.subscription = client.subscribe(id);
    }, 100);
  }
  client.on("status", (status) => {
    const unknown = /Unknown channel ID: (\d+)/.exec(status.message ?? "");
    if (unknown) subscribe(Number(unknown[1]));
  });
  const bySubscription = () => new Map([...channels.values()].map((c) => [c.subscription, c]));
  client.on("message", ({ subscriptionId, data }) => {
    const c = bySubscription().get(subscriptionId);
    if (!c) return;
    c.check(new Uint8Array(data.buffer, data.byteOffset, data.byteLength));
    counts[c.topic] = (counts[c.topic] ?? 0) + 1;
    if (wanted.every((t) => counts[t])) finish();
  });
  await new Promise((resolve) => setTimeout(resolve, seconds * 1000));
  const missing = wanted.filter((t) => !counts[t]);
  console.log(JSON.stringify({ channels: channels.size, topics: counts }));
  fail(`after ${seconds} s nothing valid had arrived on ${missing.join(", ")}`);
}

const [mode, ...rest] = process.argv.slice(2);
if (mode === "mcap" && rest.length === 1) {
  checkMcap(rest[0]);
} else if (mode === "live" && rest.length >= 2) {
  await checkLive(rest[0], Number(rest[1]), rest.slice(2));
} else {
  fail("usage: node check.mjs mcap FILE.mcap | node check.mjs live ws://HOST:PORT SECONDS TOPIC...");
}
