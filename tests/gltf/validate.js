// Validates .glb files with the Khronos glTF validator; prints one JSON line per file
// (errors, warnings, the first messages) and exits 1 if any file has an error.
const fs = require('fs');
const validator = require('gltf-validator');

async function main(paths) {
  let failed = false;
  for (const path of paths) {
    const report = await validator.validateBytes(new Uint8Array(fs.readFileSync(path)), {
      maxIssues: 20,
    });
    const issues = report.issues;
    const first = issues.messages.slice(0, 5).map((m) => `${m.code} ${m.pointer || ''}: ${m.message}`);
    console.log(JSON.stringify({ path, errors: issues.numErrors, warnings: issues.numWarnings, first }));
    failed = failed || issues.numErrors > 0;
  }
  process.exit(failed ? 1 : 0);
}

main(process.argv.slice(2)).catch((e) => {
  console.error(e);
  process.exit(2);
});
