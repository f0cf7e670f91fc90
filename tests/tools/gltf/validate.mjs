// Validates a .glb with the Khronos glTF validator and prints its report's counts as JSON.
// Usage: node validate.mjs FILE.glb   (exit 1 when the report has errors)
import { readFileSync } from "node:fs";
import validator from "gltf-validator";

const bytes = new Uint8Array(readFileSync(process.argv[2]));
const report = await validator.validateBytes(bytes);
const issues = report.issues;
console.log(JSON.stringify({
  errors: issues.numErrors, warnings: issues.numWarnings, infos: issues.numInfos,
  messages: issues.messages.filter((m) => m.severity <= 1).map((m) => `${m.code}: ${m.message} (${m.pointer ?? ""})`),
  primitives: report.info ? report.info.drawCallCount : 0,
}));
process.exit(issues.numErrors > 0 ? 1 : 0);
