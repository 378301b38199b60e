#pragma once
//! @file mjcf_source.hpp
//! An MJCF model's text as files: every file MuJoCo 2.2.2 reads to compile it, and every numeric
//! attribute checked to be a finite number before MuJoCo sees it (MuJoCo reads "nan" as 0 with only
//! a warning, and "inf" as it is).

#include <string>
#include <vector>

#include "leeway/core/error.hpp"

namespace leeway {

//! The model text could not be parsed as XML (the message names the file, line and reason).
//! load_model_file lets MuJoCo report such a file first, with its own message.
class MjcfSyntaxError : public InputError {
 public:
  using InputError::InputError;
};

//! What read_mjcf_source found.
struct MjcfSource {
  //! The model file, then every file it includes (recursively, in document order), then the mesh,
  //! height-field, skin and texture files its assets name, as paths MuJoCo 2.2.2 opens: includes
  //! relative to the model file's folder; asset files relative to <compiler meshdir> (meshes,
  //! height fields, skins) or texturedir (textures), themselves relative to the model's folder
  //! unless absolute, with strippath honoured. Asset files are listed whether or not they exist.
  std::vector<std::string> files;
};

//! Reads the MJCF file `path` and the files it includes, and checks every numeric attribute
//! (pos, quat, axisangle, xyaxes, zaxis, euler, size, fromto, range, ref, axis, mass, diaginertia,
//! margin, gap, solref, solimp, rgba, a keyframe's qpos, a custom numeric's data, every attribute of
//! <visual> and <statistic>, ...): each of its values must be a finite number.
//! @throws InputError "FILE: TAG 'NAME' ATTRIBUTE 'VALUE' is not finite (value K 'TEXT', line N)",
//! naming the file that holds the element; MjcfSyntaxError when a file is not well-formed XML.
//! An include that cannot be read is left for MuJoCo to report.
MjcfSource read_mjcf_source(const std::string& path);

//! Checks that the XML `text` (read from `file`) nests no deeper than 1,000 elements and has no
//! unterminated markup, without recursing: a tree parser (urdfdom's TinyXML) would exhaust the stack
//! on a deeply nested file before reporting anything.
//! @throws MjcfSyntaxError naming the file and the line.
void require_shallow_xml(const std::string& text, const std::string& file);

//! Every file a model file makes leeway read: a compiled model (.mjb) is itself alone, an MJCF
//! file is read_mjcf_source's list. For refusing an output that would overwrite one of them.
//! @throws InputError as read_mjcf_source.
std::vector<std::string> model_input_files(const std::string& path);

//! The first child of the root element of the MJCF file at `path` that is a model section
//! (compiler, option, asset, worldbody, keyframe, ...: what a fragment included inside <worldbody>
//! cannot hold), as "<tag> (line N)"; empty when there is none.
//! @throws InputError when the file cannot be read; MjcfSyntaxError as require_shallow_xml.
std::string first_model_section(const std::string& path);

}  // namespace leeway
