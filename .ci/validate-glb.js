// Validates GLB files with the Khronos glTF validator (npm package `gltf-validator`): prints
// each file's error, warning, info and hint counts and its messages, and exits 1 if any file
// has an error. Usage: NODE_PATH=DIR/node_modules node .ci/validate-glb.js FILE.glb...
const fs = require('fs');
const validator = require('gltf-validator');

async function main(files) {
    let failed = false;
    for (const file of files) {
        const report = await validator.validateBytes(new Uint8Array(fs.readFileSync(file)));
        const i = report.issues;
        console.log(`${file}: ${i.numErrors} errors, ${i.numWarnings} warnings, ${i.numInfos} infos, ${i.numHints} hints`);
        for (const m of i.messages) {
            console.log(`  ${['error', 'warning', 'info', 'hint'][m.severity]} ${m.code} at ${m.pointer || '-'}: ${m.message}`);
        }
        failed = failed || i.numErrors > 0;
    }
    process.exit(failed ? 1 : 0);
}

if (process.argv.length < 3) {
    console.error('usage: node .ci/validate-glb.js FILE.glb...');
    process.exit(2);
}
main(process.argv.slice(2)).catch((e) => {
    console.error(e);
    process.exit(1);
});
