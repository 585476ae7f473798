// Decodes the ros2 channels of MCAP files as Foxglove's viewers do: @mcap/core reads the
// file, @foxglove/rosmsg parses each `ros2msg` schema (ROS 2 mode) and
// @foxglove/rosmsg2-serialization's MessageReader decodes each `cdr` message.
//   node decode_ros2.mjs FILE...
// Prints {FILE: {TOPIC: {schema, schema_encoding, message_encoding, messages: [[seq,
// log_time, value, trailing bytes]]}}} as JSON that keeps every value: a BigInt as a bare
// integer, -0 as -0.0, NaN and ±Infinity as the strings "NaN", "Infinity", "-Infinity",
// typed arrays as lists.  Channels in other encodings are listed without messages.  A file
// that cannot be read, or a schema or message that cannot be decoded, gives {FILE: {error}}
// (the other files are still decoded).
import { readFile } from "node:fs/promises";
import { McapStreamReader } from "@mcap/core";
import { loadDecompressHandlers } from "@mcap/support";
import { parse } from "@foxglove/rosmsg";
import { MessageReader } from "@foxglove/rosmsg2-serialization";

const decompressHandlers = await loadDecompressHandlers();

// JSON.stringify loses -0, NaN, Infinity and cannot write a BigInt or a typed array
function toJson(v) {
  if (typeof v === "bigint") return v.toString();
  if (typeof v === "number") {
    if (Number.isNaN(v)) return '"NaN"';
    if (v === Infinity) return '"Infinity"';
    if (v === -Infinity) return '"-Infinity"';
    return Object.is(v, -0) ? "-0.0" : JSON.stringify(v);
  }
  if (v === null || v === undefined) return "null";
  if (ArrayBuffer.isView(v) || Array.isArray(v)) return `[${Array.from(v, toJson).join(",")}]`;
  if (typeof v === "object") {
    return `{${Object.entries(v).map(([k, x]) => `${JSON.stringify(k)}:${toJson(x)}`).join(",")}}`;
  }
  return JSON.stringify(v);
}

async function decode(path) {
  const stream = new McapStreamReader({ decompressHandlers, validateCrcs: true });
  stream.append(await readFile(path));
  const schemas = new Map();
  const channels = new Map();
  const topics = {};
  let record;
  while ((record = stream.nextRecord()) !== undefined) {
    if (record.type === "Schema") {
      schemas.set(record.id, record);
    } else if (record.type === "Channel" && !channels.has(record.id)) {
      // (the summary section repeats the schemas and channels)
      const schema = schemas.get(record.schemaId);
      const text = new TextDecoder().decode(schema.data);
      const ros2 = schema.encoding === "ros2msg" && record.messageEncoding === "cdr";
      let reader;
      try {
        reader = ros2 ? new MessageReader(parse(text, { ros2: true })) : undefined;
      } catch (err) {
        throw new Error(`topic '${record.topic}': schema '${schema.name}': ${err.message}`);
      }
      channels.set(record.id, { topic: record.topic, reader });
      topics[record.topic] = { schema: schema.name, schema_encoding: schema.encoding,
                               message_encoding: record.messageEncoding, messages: [] };
    } else if (record.type === "Message") {
      const { topic, reader } = channels.get(record.channelId);
      if (reader === undefined) continue;
      let value;
      try {
        value = reader.readMessage(record.data);
      } catch (err) {
        throw new Error(`topic '${topic}' message ${record.sequence}: ${err.message}`);
      }
      const trailing = record.data.byteLength - reader.lastReadByteLength();
      topics[topic].messages.push([record.sequence, record.logTime, value, trailing]);
    }
  }
  if (!stream.done()) throw new Error("the file ends inside a record");
  return topics;
}

const results = {};
for (const path of process.argv.slice(2)) {
  try {
    results[path] = await decode(path);
  } catch (err) {
    results[path] = { error: String(err?.message ?? err) };
  }
}
process.stdout.write(toJson(results));
