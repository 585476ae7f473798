; Scopes, definitions and references of .lnc files: processes, states, groups and
; templates by name, defines and template parameters by %(name).

(source_file) @local.scope

; A template's parameters are seen only in its body.
(template_section) @local.scope

(process_section
  name: (section_name) @local.definition.type)

(state_section
  name: (section_name) @local.definition.type)

(group_section
  name: (section_name) @local.definition.type)

; The name itself is seen in the whole file (Neovim's hoisting to the parent scope).
((template_section
  name: (template_name) @local.definition.macro)
  (#set! definition.macro.scope "parent"))

(template_parameter
  name: (identifier) @local.definition.parameter)

(defines_section
  [
    (key_line
      key: (key) @local.definition.constant)
    (conditional
      line: (key_line
        key: (key) @local.definition.constant))
  ])

; Names of processes, states and groups in depends_on, start_before, start_on_ready
; and members.
(list
  (list_item) @local.reference)

(expansion
  name: (define_name) @local.reference)

(conditional
  name: (define_name) @local.reference)

(template_use
  template: (template_name) @local.reference)
