// SPDX-License-Identifier: GPL-3.0-or-later
// Reads an E57 file with web-e57 (npm; the Rust `e57` crate built to WebAssembly, an
// implementation independent of pointsurf) and writes its points as "x y z r g b" lines.
// Usage: node e57_interop.mjs WEB_E57_PACKAGE_DIR IN.e57 OUT.xyz
import { promises as fs } from "fs";
import path from "path";
import { pathToFileURL } from "url";

const [dir, input, output] = process.argv.slice(2);
const bg = await import(pathToFileURL(path.join(dir, "e57_bg.js")).href);
const { instance } = await WebAssembly.instantiate(await fs.readFile(path.join(dir, "e57_bg.wasm")), { "./e57_bg.js": bg });
bg.__wbg_set_wasm(instance.exports);
await fs.writeFile(output, bg.convertE57(new Uint8Array(await fs.readFile(input)), "XYZ"));
