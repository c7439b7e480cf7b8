// Writes scenes/models/bunny.ply (binary little endian: float x y z, uchar/int faces) from the npm
// package `bunny` (version 1.0.1, licence "Public Domain" in its package.json; repository
// github.com/mikolalysenko/bunny). The package ships the Stanford bunny as JSON-like arrays
// (`positions`, 1839 vertices, and `cells`, 3674 triangles): the Stanford 3D Scanning
// Repository's bunny (Turk and Levoy, 1994; graphics.stanford.edu/data/3Dscanrep), reduced.
// The coordinates are written as float32 exactly as the package gives them (y up, about 10
// units tall); scenes/bunny_room.json scales, turns and places it.
//
// Usage, from the repository root:
//   npm pack bunny@1.0.1 && tar xzf bunny-1.0.1.tgz     # unpacks ./package/index.js
//   node scenes/models/make_bunny_ply.mjs package/index.js scenes/models/bunny.ply
import { createRequire } from "node:module";
import { writeFileSync } from "node:fs";
import { resolve } from "node:path";

const [src = "bunny", out = "scenes/models/bunny.ply"] = process.argv.slice(2);
const require = createRequire(import.meta.url);
const bunny = require(src === "bunny" ? "bunny" : resolve(src));
const { positions, cells } = bunny;

const header =
  "ply\n" +
  "format binary_little_endian 1.0\n" +
  "comment Stanford bunny (Stanford 3D Scanning Repository), from npm bunny@1.0.1 (Public Domain)\n" +
  "comment written by scenes/models/make_bunny_ply.mjs\n" +
  `element vertex ${positions.length}\n` +
  "property float x\nproperty float y\nproperty float z\n" +
  `element face ${cells.length}\n` +
  "property list uchar int vertex_indices\n" +
  "end_header\n";
const body = Buffer.alloc(positions.length * 12 + cells.length * 13);
let o = 0;
for (const p of positions) {
  for (const x of p) o = body.writeFloatLE(x, o);
}
for (const c of cells) {
  if (c.length !== 3) throw new Error(`cell of ${c.length} vertices`);
  o = body.writeUInt8(3, o);
  for (const i of c) o = body.writeInt32LE(i, o);
}
writeFileSync(out, Buffer.concat([Buffer.from(header, "ascii"), body]));
console.log(`wrote ${out}: ${positions.length} vertices, ${cells.length} triangles`);
