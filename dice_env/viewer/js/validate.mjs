// Validate a binary glTF with the Khronos glTF validator: `node validate.mjs FILE.glb`.
// Prints the validator's JSON report; exits 1 when it reports errors, 2 on bad usage.
import { readFile } from "node:fs/promises";
import { basename } from "node:path";
import validator from "gltf-validator";

const [path] = process.argv.slice(2);
if (!path) {
  console.error("usage: node validate.mjs FILE.glb");
  process.exit(2);
}
const report = await validator.validateBytes(new Uint8Array(await readFile(path)), {
  uri: basename(path),
  format: "glb",
  maxIssues: 0,
  writeTimestamp: false,
});
console.log(JSON.stringify(report, null, 2));
process.exit(report.issues.numErrors > 0 ? 1 : 0);
