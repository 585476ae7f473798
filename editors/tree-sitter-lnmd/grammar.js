/**
 * Tree-sitter grammar of Links and Nodes message definitions (md files), the language
 * of docs/message_definitions.md; ln_generate/tokenizer.py and parser.py are the reference.
 * Line oriented: one construct per line, so newlines are tokens and `#` comments extras.
 */

// The built-in types and their aliases (docs/message_definitions.md, "Types").
const PRIMITIVE_TYPES = [
  'char', 'int8_t', 'uint8_t', 'int16_t', 'short', 'uint16_t', 'int32_t', 'int',
  'uint32_t', 'int64_t', 'uint64_t', 'float', 'float32_t', 'double', 'float64_t',
];
const SECTION_KEYWORDS = ['request', 'response', 'connect', 'call'];

module.exports = grammar({
  name: 'lnmd',

  // A newline is not whitespace here; a byte order mark may start the file.
  extras: $ => [/[ \t\r\f\v\uFEFF]/, $.comment],

  word: $ => $.identifier,

  // At a newline inside a section the parser cannot yet tell whether the section goes on
  // or the next line starts a new one; the token after the newline decides.
  conflicts: $ => [[$.section]],

  rules: {
    // Lines are separated by newlines, so the last line needs none. Fields, defines and
    // `service`/`event` come first; a section runs from its header to the next one.
    source_file: $ => seq(
      optional($._head_item),
      repeat(seq($._newline, optional($._head_item))),
      repeat(seq($._newline, $.section)),
    ),

    _head_item: $ => choice($.kind_declaration, $.define_declaration, $.field_declaration),

    _section_item: $ => choice($.define_declaration, $.field_declaration),

    kind_declaration: _ => choice('service', 'event'),

    section: $ => seq(
      field('header', $.section_header),
      repeat(seq($._newline, optional($._section_item))),
    ),

    section_header: _ => choice(...SECTION_KEYWORDS),

    define_declaration: $ => seq(
      'define',
      field('name', alias($.identifier, $.type_identifier)),
      'as',
      field('md', $.string),
    ),

    // `TYPE NAME`, `TYPE NAME[SIZE]` or `TYPE* NAME` (a dynamic field has no static size).
    field_declaration: $ => choice(
      seq(field('type', $._type), $._field_name, optional(field('size', $.array_size))),
      seq(field('type', choice($._type, $._define_as_type)), $.dynamic, $._field_name),
    ),

    _field_name: $ => field('name', alias($.identifier, $.field_identifier)),

    // `define` followed by a name starts a define; followed by `*` it is a type.
    _define_as_type: $ => alias('define', $.type_identifier),

    // As in ln_generate, a line with more than one token is a field: its type may be
    // spelled like a keyword (an imported md named `event`; ln_generate says if unknown).
    _type: $ => choice(
      $.primitive_type,
      alias($.identifier, $.type_identifier),
      ...['service', 'event', ...SECTION_KEYWORDS].map(word => alias(word, $.type_identifier)),
    ),

    primitive_type: _ => choice(...PRIMITIVE_TYPES),

    // `TYPE* NAME`: a dynamic field (a length and a pointer in memory).
    dynamic: _ => '*',

    array_size: $ => seq('[', $._expression, ']'),

    _expression: $ => choice(
      $.number,
      $.parenthesized_expression,
      $.unary_expression,
      $.binary_expression,
    ),

    parenthesized_expression: $ => seq('(', $._expression, ')'),

    unary_expression: $ => prec(3, seq(
      field('operator', choice('+', '-')),
      field('argument', $._expression),
    )),

    binary_expression: $ => choice(
      ...[['+', 1], ['-', 1], ['*', 2], ['/', 2]].map(([operator, precedence]) =>
        prec.left(precedence, seq(
          field('left', $._expression),
          field('operator', operator),
          field('right', $._expression),
        )),
      ),
    ),

    number: _ => /0[xX][0-9A-Fa-f]+|[0-9]+/,

    // An md name: no escapes, on one line.
    string: _ => /"[^"\n]*"/,

    identifier: _ => /[A-Za-z_][A-Za-z0-9_]*/,

    comment: _ => token(seq('#', /[^\n]*/)),

    _newline: _ => '\n',
  },
});
