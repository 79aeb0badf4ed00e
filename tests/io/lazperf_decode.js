// SPDX-License-Identifier: GPL-3.0-or-later
// Decodes a LAZ file with laz-perf (the npm registry's WASM build of laz-perf, an independent
// LAZ implementation) and writes the same file uncompressed: the header and VLRs as they are,
// the compression bits of the point format cleared, then the decoded point records.
//   node lazperf_decode.js LAZPERF_MODULE_DIR in.laz out.las      (out.las '-': decode only)
// Prints the points decoded and the seconds the decoding took (for bench/io).
'use strict';
const fs = require('fs');
const { createLazPerf } = require(process.argv[2]);

(async () => {
  const [input, output] = process.argv.slice(3);
  const LazPerf = await createLazPerf();
  const bytes = fs.readFileSync(input);
  const pointOffset = bytes.readUInt32LE(96);
  const file = LazPerf._malloc(bytes.length);
  LazPerf.HEAPU8.set(bytes, file);
  const laszip = new LazPerf.LASZip();
  laszip.open(file, bytes.length);
  const count = laszip.getCount();
  const length = laszip.getPointLength();
  const point = LazPerf._malloc(length);
  const out = output === '-' ? null : Buffer.alloc(pointOffset + count * length);
  if (out) {
    bytes.copy(out, 0, 0, pointOffset);
    out[104] &= 0x3f;
  }
  const start = process.hrtime.bigint();
  for (let i = 0; i < count; ++i) {
    laszip.getPoint(point);
    if (out) out.set(LazPerf.HEAPU8.subarray(point, point + length), pointOffset + i * length);
  }
  const seconds = Number(process.hrtime.bigint() - start) / 1e9;
  if (out) fs.writeFileSync(output, out);
  laszip.delete();
  console.log(`${count} ${seconds}`);
})().catch((e) => {
  console.error(`lazperf_decode.js: ${e}`);
  process.exit(1);
});
