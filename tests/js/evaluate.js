// Evaluate a generated JavaScript module for the tests: reads {module, calls} as JSON on stdin,
// writes one result per call (its outputs, flattened row-major, in the order of FUNCTIONS) as
// JSON on stdout.  Non-finite numbers travel as the strings "NaN", "Infinity", "-Infinity";
// a call that throws gives {"error": message}.
"use strict";
const fs = require("fs");

const request = JSON.parse(fs.readFileSync(0, "utf8"));
const model = require(request.module);

function flatten(value, into) {
  if (Array.isArray(value)) {
    for (const v of value) flatten(v, into);
  } else {
    into.push(Number.isFinite(value) ? value : String(value));
  }
  return into;
}

const results = request.calls.map(({ function: name, args, params }) => {
  const outputs = Object.keys(model.FUNCTIONS[name].outputs);
  try {
    const value = model[name](...args, ...(params === undefined ? [] : [params]));
    return outputs.length > 1 ? outputs.map((o) => flatten(value[o], [])) : [flatten(value, [])];
  } catch (error) {
    return { error: error.message };
  }
});
process.stdout.write(JSON.stringify(results));
