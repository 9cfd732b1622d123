"""The spec room: shape spec files read, validated and parsed (grammar, names, params), the one public entry
(entry.py: load_spec, parse_spec, with the parsed-spec cache an explicit choice), the `Spec` type, the key of
a spec's generated code, and the gallery of famous surfaces. Below codegen/: nothing here derives or emits."""
