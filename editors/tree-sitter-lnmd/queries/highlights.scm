; Highlighting of message definitions: keywords, types, field names, array sizes.

(comment) @comment

(kind_declaration) @keyword

(section_header) @keyword

[
  "define"
  "as"
] @keyword.import

(primitive_type) @type.builtin

(field_declaration
  type: (type_identifier) @type)

(define_declaration
  name: (type_identifier) @type.definition)

(define_declaration
  md: (string) @string.special.path)

(field_identifier) @property

(dynamic) @punctuation.special

(number) @number

(binary_expression
  operator: _ @operator)

(unary_expression
  operator: _ @operator)

[
  "["
  "]"
  "("
  ")"
] @punctuation.bracket
