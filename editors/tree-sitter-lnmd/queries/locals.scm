; Scopes, definitions and references of message definitions: a file is one scope; a
; `define` names a type that fields use, and each field defines its name.

(source_file) @local.scope

(define_declaration
  name: (type_identifier) @local.definition)

(field_declaration
  name: (field_identifier) @local.definition)

(field_declaration
  type: (type_identifier) @local.reference)
