//! Malformed models: each file under `tests/malformed/` has exactly one error, and the
//! reader must report it with this exact message, `file:line:col: element 'name': msg`.
//! Cases marked "needs expr parser" depend on the real expression parser (function
//! calls); cases 04-06 assert expression-parser messages too. All 56 were checked
//! against branch `expr` at 6bdcfb1 (merged into a scratch copy): remove the `ignore`s
//! when merging.

use mbfmu::model::load_str;

/// Load `tests/malformed/<file>` (labelled by its file name) and check the message.
fn check(file: &str, expected: &str) {
    let path = format!("{}/tests/malformed/{file}", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
    match load_str(&text, file) {
        Ok(_) => panic!("{file}: loaded, expected error: {expected}"),
        Err(e) => assert_eq!(e.to_string(), expected, "{file}"),
    }
}

macro_rules! case {
    ($(#[$attr:meta])* $name:ident, $file:expr, $expected:expr) => {
        #[test]
        $(#[$attr])*
        fn $name() {
            check($file, $expected);
        }
    };
}

case!(m01_unknown_element, "01_unknown_element.xml", "01_unknown_element.xml:2:3: bodie 'b': unknown element");

case!(
    m02_unknown_attribute,
    "02_unknown_attribute.xml",
    "02_unknown_attribute.xml:2:60: body 'b': unknown attribute 'colour'"
);

case!(
    m03_missing_attribute,
    "03_missing_attribute.xml",
    "03_missing_attribute.xml:2:3: body 'b': missing required attribute 'mass'"
);

case!(
    m04_bad_number,
    "04_bad_number.xml",
    "04_bad_number.xml:2:24: body 'b': bad expression in 'mass': bad number '1.2.3'"
);

case!(
    m05_bad_expression,
    "05_bad_expression.xml",
    "05_bad_expression.xml:2:32: body 'b': bad expression in 'mass': unexpected end of expression"
);

case!(
    m06_unknown_parameter,
    "06_unknown_parameter.xml",
    "06_unknown_parameter.xml:3:26: body 'b': bad expression in 'mass': unknown name 'q'"
);

case!(
    m07_unknown_function,
    "07_unknown_function.xml",
    "07_unknown_function.xml:4:34: constraint 'c': bad expression in 'function': unknown function 'foo'"
);

case!(
    m08_wrong_argument_count,
    "08_wrong_argument_count.xml",
    "08_wrong_argument_count.xml:4:34: constraint 'c': bad expression in 'function': 'atan2' takes 2 arguments, got 1"
);

case!(
    m09_unknown_marker_in_function,
    "09_unknown_marker_in_function.xml",
    "09_unknown_marker_in_function.xml:4:37: constraint 'c': bad expression in 'function': unknown marker 'b.nope'"
);

case!(m10_unknown_marker, "10_unknown_marker.xml", "10_unknown_marker.xml:4:38: joint 'j': unknown marker 'b.nope'");

case!(
    m11_duplicate_body,
    "11_duplicate_body.xml",
    "11_duplicate_body.xml:3:9: body 'b': duplicate body name 'b' (first defined at line 2)"
);

case!(
    m12_duplicate_marker,
    "12_duplicate_marker.xml",
    "12_duplicate_marker.xml:4:13: marker 'p': duplicate marker name 'p' (first defined at line 3)"
);

case!(
    m13_duplicate_force,
    "13_duplicate_force.xml",
    "13_duplicate_force.xml:5:11: sforce 'f': duplicate force name 'f' (first defined at line 4)"
);

case!(
    m14_duplicate_parameter,
    "14_duplicate_parameter.xml",
    "14_duplicate_parameter.xml:3:14: parameter 'a': duplicate parameter name 'a' (first defined at line 2)"
);

case!(
    m15_invalid_name,
    "15_invalid_name.xml",
    "15_invalid_name.xml:2:9: body '2b': invalid name '2b' (names are [A-Za-z_][A-Za-z0-9_]*)"
);

case!(
    m16_reserved_name,
    "16_reserved_name.xml",
    "16_reserved_name.xml:2:14: parameter 'time': invalid name 'time' (reserved word)"
);

case!(
    m17_marker_named_cm,
    "17_marker_named_cm.xml",
    "17_marker_named_cm.xml:3:13: marker 'cm': invalid name 'cm' (reserved for the implicit centre-of-mass marker)"
);

case!(
    m18_function_name,
    "18_function_name.xml",
    "18_function_name.xml:2:9: body 'sin': invalid name 'sin' (it is a function name)"
);

case!(
    m19_joint_same_body,
    "19_joint_same_body.xml",
    "19_joint_same_body.xml:5:3: joint 'j': markers i and j are both on the same body 'b'"
);

case!(
    m20_motion_wrong_joint,
    "20_motion_wrong_joint.xml",
    "20_motion_wrong_joint.xml:4:31: motion 'mo': dof 'rotation' needs a revolute or cylindrical joint; joint 'j' is translational"
);

case!(m21_zero_mass, "21_zero_mass.xml", "21_zero_mass.xml:2:18: body 'b': mass must be positive (got 0)");

case!(
    m22_inertia_not_positive_definite,
    "22_inertia_not_positive_definite.xml",
    "22_inertia_not_positive_definite.xml:2:27: body 'b': inertia is not positive definite"
);

case!(
    m23_constraint_uses_input,
    "23_constraint_uses_input.xml",
    "23_constraint_uses_input.xml:3:24: constraint 'c': 'function' may use only positions, time and parameters (it uses inputs)"
);

case!(
    m24_motion_uses_input,
    "24_motion_uses_input.xml",
    "24_motion_uses_input.xml:6:46: motion 'mo': 'function' may use only time and parameters (it uses inputs)"
);

case!(
    m25_constraint_uses_velocity,
    "25_constraint_uses_velocity.xml",
    "25_constraint_uses_velocity.xml:4:24: constraint 'c': 'function' may use only positions, time and parameters (it uses velocities)"
);

case!(
    m26_motion_uses_marker,
    "26_motion_uses_marker.xml",
    "26_motion_uses_marker.xml:5:46: motion 'mo': 'function' may use only time and parameters (it uses marker measures)"
);

case!(
    m27_implicit_without_rate,
    "27_implicit_without_rate.xml",
    "27_implicit_without_rate.xml:3:52: differential 'x': implicit: 'function' must use dif1(x)"
);

case!(
    m28_gforce_load_unknown_element,
    "28_gforce_load_unknown_element.xml",
    "28_gforce_load_unknown_element.xml:5:39: gforce 'g': bad expression in 'force': unknown element 'jj'"
);

case!(
    m29_ic_on_wrong_joint,
    "29_ic_on_wrong_joint.xml",
    "29_ic_on_wrong_joint.xml:4:59: joint 'j': attribute 'ic_angle' is not allowed on a translational joint (only revolute and cylindrical)"
);

case!(
    m30_bad_version,
    "30_bad_version.xml",
    "30_bad_version.xml:1:21: multibody 'm': unsupported version '2' (this reader knows version \"1\")"
);

case!(m31_two_roots, "31_two_roots.xml", "31_two_roots.xml:3:1: multibody 'n': more than one root element");

case!(
    m32_ground_twice,
    "32_ground_twice.xml",
    "32_ground_twice.xml:3:3: ground 'ground': only one <ground> element is allowed (first at line 2)"
);

case!(
    m33_gravity_twice,
    "33_gravity_twice.xml",
    "33_gravity_twice.xml:3:3: gravity 'gravity': only one <gravity> element is allowed (first at line 2)"
);

case!(
    m34_experiment_twice,
    "34_experiment_twice.xml",
    "34_experiment_twice.xml:3:3: experiment 'experiment': only one <experiment> element is allowed (first at line 2)"
);

case!(
    m35_bushing_stiffness_count,
    "35_bushing_stiffness_count.xml",
    "35_bushing_stiffness_count.xml:4:44: bushing 'bu': attribute 'stiffness' needs 6 items, found 5"
);

case!(
    m36_vector_item_count,
    "36_vector_item_count.xml",
    "36_vector_item_count.xml:2:43: body 'b': attribute 'position' needs 3 items, found 2"
);

case!(
    m37_parameter_cycle,
    "37_parameter_cycle.xml",
    "37_parameter_cycle.xml:2:3: parameter 'a': dependency cycle a -> b -> a"
);

case!(
    m38_euler_and_z_axis,
    "38_euler_and_z_axis.xml",
    "38_euler_and_z_axis.xml:2:77: body 'b': give either euler313 or z_axis [x_axis], not both"
);

case!(m39_zero_z_axis, "39_zero_z_axis.xml", "39_zero_z_axis.xml:2:45: marker 'O': z_axis is zero");

case!(
    m40_x_axis_parallel,
    "40_x_axis_parallel.xml",
    "40_x_axis_parallel.xml:2:75: body 'b': x_axis is zero or parallel to z_axis"
);

case!(
    m41_wrong_root,
    "41_wrong_root.xml",
    "41_wrong_root.xml:1:1: model 'm': root element must be <multibody>, found <model>"
);

case!(
    m42_not_constant,
    "42_not_constant.xml",
    "42_not_constant.xml:2:24: body 'b': 'mass' must be a constant expression (numbers, pi, parameters)"
);

case!(
    m43_spring_missing_length,
    "43_spring_missing_length.xml",
    "43_spring_missing_length.xml:4:3: spring_damper 'k': missing required attribute 'length'"
);

case!(
    m44_bad_keyword,
    "44_bad_keyword.xml",
    "44_bad_keyword.xml:4:19: joint 'j': bad value 'hinge' for 'type' (expected fixed, revolute, translational, cylindrical, universal, spherical, planar)"
);

case!(
    m45_duplicate_linearization_state,
    "45_duplicate_linearization_state.xml",
    "45_duplicate_linearization_state.xml:4:12: state 's': duplicate linearization state name 's' (first defined at line 3)"
);

case!(m46_unexpected_text, "46_unexpected_text.xml", "46_unexpected_text.xml:2:3: multibody 'm': unexpected text");

case!(
    m47_malformed_xml,
    "47_malformed_xml.xml",
    "47_malformed_xml.xml:3:1: xml 'document': malformed XML: ill-formed document: expected `</body>`, but `</multibody>` was found"
);

case!(m48_unknown_joint, "48_unknown_joint.xml", "48_unknown_joint.xml:4:28: motion 'mo': unknown joint 'nope'");

case!(
    m49_negative_mass_from_parameter,
    "49_negative_mass_from_parameter.xml",
    "49_negative_mass_from_parameter.xml:3:18: body 'b': mass must be positive (got -2)"
);

case!(
    m50_lin_velocity_uses_input,
    "50_lin_velocity_uses_input.xml",
    "50_lin_velocity_uses_input.xml:4:24: velocity 'v': 'function' may use only positions, velocities, time and parameters (it uses inputs)"
);

case!(
    m51_marker_outside_owner,
    "51_marker_outside_owner.xml",
    "51_marker_outside_owner.xml:2:3: marker 'p': element <marker> is not allowed inside <multibody>"
);

case!(
    m52_nonfinite_value,
    "52_nonfinite_value.xml",
    "52_nonfinite_value.xml:3:53: body 'b': 'position' evaluates to inf"
);

case!(
    m53_name_used_by_other_kind,
    "53_name_used_by_other_kind.xml",
    "53_name_used_by_other_kind.xml:3:10: input 'u': name 'u' is already used by parameter at line 2"
);

case!(
    m54_bad_static_flag,
    "54_bad_static_flag.xml",
    "54_bad_static_flag.xml:2:13: analysis 'analysis': bad value 'yes' for 'static' (expected true, false)"
);

case!(
    m55_x_axis_without_z_axis,
    "55_x_axis_without_z_axis.xml",
    "55_x_axis_without_z_axis.xml:2:60: body 'b': x_axis needs z_axis"
);

case!(
    m56_spring_angle_on_translational,
    "56_spring_angle_on_translational.xml",
    "56_spring_angle_on_translational.xml:4:93: spring_damper 'k': attribute 'angle' is not allowed on a translational spring_damper (use 'length')"
);

case!(
    m57_state_name_clash,
    "57_state_name_clash.xml",
    "57_state_name_clash.xml:5:12: state 'height': name 'height' is already used by output at line 3"
);

case!(
    m58_load_of_user_constraint,
    "58_load_of_user_constraint.xml",
    "58_load_of_user_constraint.xml:4:27: output 'reaction': 'function' reads the load of a user constraint, which has no load"
);

case!(
    m59_bad_unit,
    "59_bad_unit.xml",
    "59_bad_unit.xml:2:34: parameter 'c': attribute 'unit': 'Ns/m' is not a unit: 'Ns' is not a unit symbol (write factors joined by '.', e.g. 'N.s/m', 'kg.m2', 'm/s2')"
);

case!(
    m60_bad_unit_exponent,
    "60_bad_unit_exponent.xml",
    "60_bad_unit_exponent.xml:2:19: input 'F': attribute 'unit': 'm^2' is not a unit: 'm^' is not a unit symbol (write factors joined by '.', e.g. 'N.s/m', 'kg.m2', 'm/s2')"
);

// Found by the model_loader fuzz target (fuzz/): models the reader accepted and the
// engine then refused without a location (System::from_model).

case!(
    m61_variable_touches_five_bodies,
    "61_variable_touches_five_bodies.xml",
    "61_variable_touches_five_bodies.xml:7:22: variable 'v': touches 5 bodies (b1, b2, b3, b4, b5); an element may touch at most 4 (measure some of them in <variable> elements and use those)"
);

case!(
    m62_gforce_touches_five_bodies,
    "62_gforce_touches_five_bodies.xml",
    "62_gforce_touches_five_bodies.xml:10:76: gforce 'g': touches 5 bodies (b1, b2, b3, b4, b5); an element may touch at most 4 (measure some of them in <variable> elements and use those)"
);

case!(
    m63_reads_load_of_load_reader,
    "63_reads_load_of_load_reader.xml",
    "63_reads_load_of_load_reader.xml:4:22: variable 'v': 'function' reads the load of sforce 's' (line 5), which reads loads itself; forces and user elements may read only loads that read no loads"
);

case!(
    m64_sforce_reads_own_load,
    "64_sforce_reads_own_load.xml",
    "64_sforce_reads_own_load.xml:4:55: sforce 's': 'function' reads the load of sforce 's' (line 4), which reads loads itself; forces and user elements may read only loads that read no loads"
);

// A UTF-8 byte order mark (fuzz input EF BB BF 0A 0A 3C 0A was reported at 1:3, past the
// end of line 1): positions from the XML reader counted from after the mark, 3 bytes
// early; and the mark is no column. A second mark is text (a first fix, stripping the
// mark before the XML reader, let the reader skip the second one uncounted: fuzz input
// EF BB BF EF BB BF 3C ... reported at 1:16 of an 11-character line).

case!(
    m65_bom_malformed_xml,
    "65_bom_malformed_xml.xml",
    "65_bom_malformed_xml.xml:3:3: xml 'document': malformed XML: ill-formed document: expected `</body>`, but `</bodyx>` was found"
);

case!(
    m66_bom_unexpected_text,
    "66_bom_unexpected_text.xml",
    "66_bom_unexpected_text.xml:3:3: multibody 'm': unexpected text"
);

case!(
    m67_bom_bad_version,
    "67_bom_bad_version.xml",
    "67_bom_bad_version.xml:1:21: multibody 'm': unsupported version '2' (this reader knows version \"1\")"
);

case!(
    m70_two_byte_order_marks,
    "70_two_byte_order_marks.xml",
    "70_two_byte_order_marks.xml:1:1: multibody 'multibody': unexpected text"
);

// Positions inside attribute values count characters as written: a `\r\n` line end and an
// entity are one character of the value as read (both were counted as written before;
// the model_loader fuzz target now checks that CRLF line ends change no position).

case!(
    m68_crlf_in_expression,
    "68_crlf_in_expression.xml",
    "68_crlf_in_expression.xml:4:10: output 'y': bad expression in 'function': unknown name 'q'"
);

case!(
    m69_entity_in_expression,
    "69_entity_in_expression.xml",
    "69_entity_in_expression.xml:3:42: output 'y': bad expression in 'function': unknown name 'q'"
);

case!(
    m71_state_touches_five_bodies,
    "71_state_touches_five_bodies.xml",
    "71_state_touches_five_bodies.xml:8:21: state 's': touches 5 bodies (a, b, c, d, e); an element may touch at most 4"
);
