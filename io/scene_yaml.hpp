// Scene input: a YAML file checked against a strict schema and turned into a resolved Scene.
// The layout of the file is documented at the top of scene_yaml.cpp and in docs/SCENES.md.
//
// Every problem (unknown key, wrong type, value out of range, bad enum string, missing required
// key, missing file, YAML syntax error) throws sphdem::InputError with a message of the form
//     <file>:<line>: <dotted.key>: <what>
// e.g. "dam.yaml:7: sph.dp: value -0.001 is out of range; allowed (0, 1]". Errors that come from a
// command-line override name the override instead of the file: "--set sph.dp=-1: sph.dp: ...".
#pragma once

#include <string>
#include <vector>

#include "scene/scene.hpp"

namespace sphdem {

// Reads, validates and resolves the scene file at `path`. `overrides` are "dotted.key=value"
// strings (e.g. "sph.dp=0.002", "gravity=[0,0,-9.8]", "solids[0].shape.thickness=0.02"); each value
// is parsed as YAML and replaces (or adds) that key in the tree before validation. Overriding a
// key the schema does not know is an error. Mesh files are looked up relative to the scene file's
// folder.
Scene load_scene(const std::string& path, const std::vector<std::string>& overrides = {});

// The same from YAML text. `source_name` is used in error messages, stored in Scene::source, and
// its folder is the base for relative mesh paths.
Scene parse_scene(const std::string& yaml_text, const std::string& source_name,
                  const std::vector<std::string>& overrides = {});

}  // namespace sphdem
