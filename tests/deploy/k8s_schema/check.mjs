// Every object in deploy/k8s validated against the Kubernetes OpenAPI schema of its kind
// (kubernetes-models: field names, types, required fields, enums), which validate_deploy.py's
// cross-file checks do not cover.
//   node check.mjs DIR
import fs from "node:fs";
import path from "node:path";
import YAML from "yaml";

const dir = process.argv[2];
if (!dir) {
  console.error("usage: node check.mjs DIR");
  process.exit(2);
}
let valid = 0, invalid = 0;
for (const file of fs.readdirSync(dir).filter((f) => f.endsWith(".yaml") && f !== "kustomization.yaml").sort()) {
  for (const doc of YAML.parseAllDocuments(fs.readFileSync(path.join(dir, file), "utf8"))) {
    if (doc.errors.length) {
      console.log(`INVALID ${file}: ${doc.errors[0].message}`);
      invalid++;
      continue;
    }
    const obj = doc.toJS();
    if (!obj) continue;
    const what = `${file} ${obj.kind}/${obj.metadata?.name}`;
    let Model;
    try {
      Model = (await import(`kubernetes-models/${obj.apiVersion}/${obj.kind}`))[obj.kind];
    } catch (e) {
      console.log(`INVALID ${what}: no schema for ${obj.apiVersion} ${obj.kind}`);
      invalid++;
      continue;
    }
    try {
      new Model(obj).validate();
      console.log(`ok ${what}`);
      valid++;
    } catch (e) {
      console.log(`INVALID ${what}: ${e.message}`);
      invalid++;
    }
  }
}
console.log(`${valid} passed, ${invalid} failed`);
process.exit(invalid || !valid ? 1 : 0);
