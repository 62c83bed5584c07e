// The Khronos glTF Validator (npm gltf-validator, installed by `python3 -m explorer test` into the cache
// folder that NODE_PATH names) on each .glb given: one JSON report per line.
const validator = require('gltf-validator');
const fs = require('fs');

(async () => {
  for (const path of process.argv.slice(2)) {
    const report = await validator.validateBytes(new Uint8Array(fs.readFileSync(path)), {maxIssues: 500});
    console.log(JSON.stringify(report));
  }
})().catch((error) => { console.error(String(error)); process.exit(2); });
