/**
 * Tree-sitter grammar of the Links and Nodes configuration language (`.lnc`), the
 * language of docs/configuration.md; python/links_and_nodes/manager/config/ (lexer.py,
 * parser.py, directives.py, expand.py, templates.py) is the reference.
 * Line oriented: newlines are tokens that separate lines, `#` comments are extras.
 */

// Section words of lexer.py: sections without a name, and those with one.
const PLAIN_SECTIONS = {
  instance_section: 'instance',
  defines_section: 'defines',
  hosts_section: 'hosts',
  node_map_section: 'node_map',
  topics_section: 'topics',
  access_section: 'access',
};
const NAMED_SECTIONS = {
  process_section: 'process',
  state_section: 'state',
  group_section: 'group',
  network_section: 'network',
  logger_section: 'logger',
};
const SECTION_WORDS = [
  ...Object.values(PLAIN_SECTIONS), ...Object.values(NAMED_SECTIONS),
  'template', 'process_template',
];
// Directives of directives.py taking a value (`use_template` has its own rule).
const DIRECTIVES = [
  'include', 'optional_include', 'include_glob', 'optional_include_glob', 'pipe_include',
  'push_name_prefix', 'pop_name_prefix', 'add_message_definition_dir', 'requires_version',
  'add_process_default_template',
];
// Builtin functions of expand.py.
const FUNCTIONS = [
  'env', 'dirname', 'basename', 'subst', 'get_port_from_string', 'shell',
  'ifdef', 'ifndef', 'ifeq', 'ifexists',
];
// Keys whose values are comma lists of process, state or group names.
const LIST_KEYS = ['depends_on', 'start_before', 'start_on_ready', 'members'];

// One character of unquoted text: not blank, `#`, `"`, nor the `%` of a `%(` call;
// `stop` lists further characters that end the text.
const char = (stop) => `[^\\s#"%${stop}]|%[^\\s#"%(${stop}]`;
// Text with inner blanks but none at its ends.
const text = (first, rest) => new RegExp(`(${first})([ \\t]*(${rest}))*`);

/** A line-separated body: each line follows a newline. */
const lines = ($) => repeat(seq($._newline, optional($._line)));

/** Items separated by commas; an item may be empty (`a,,b`), but not all of them. */
const commaList = (item) => choice(
  seq(item, repeat(seq(',', optional(item)))),
  repeat1(seq(',', optional(item))),
);

module.exports = grammar({
  name: 'lnc',

  // A newline is not whitespace here; a byte order mark may start the file.
  extras: $ => [/[ \t\r\f\v\uFEFF]/, $.comment],

  supertypes: $ => [$._section],

  // Whether a newline goes on a section or ends it is known from the next token only:
  // a section header starts a new section.
  conflicts: $ => [
    ...Object.keys(PLAIN_SECTIONS).map(name => [$[name]]),
    ...Object.keys(NAMED_SECTIONS).map(name => [$[name]]),
    [$.template_section],
  ],

  rules: {
    // Lines before the first section belong to the section of the including file. A
    // section header starts a line: the file or a newline comes before it.
    source_file: $ => choice(
      seq(optional($._line), lines($), repeat(seq($._newline, $._section))),
      seq($._section, repeat(seq($._newline, $._section))),
    ),

    _section: $ => choice(
      ...Object.keys(PLAIN_SECTIONS).map(name => $[name]),
      ...Object.keys(NAMED_SECTIONS).map(name => $[name]),
      $.template_section,
    ),

    ...Object.fromEntries(Object.entries(PLAIN_SECTIONS).map(([name, word]) =>
      [name, $ => seq(word, lines($))])),

    ...Object.fromEntries(Object.entries(NAMED_SECTIONS).map(([name, word]) =>
      [name, $ => seq(word, field('name', $.section_name), lines($))])),

    // `template NAME(PARAM, PARAM2="default")`: the lines after it are its body.
    template_section: $ => seq(
      choice('template', 'process_template'),
      field('name', $.template_name),
      optional(field('parameters', $.template_parameters)),
      lines($),
    ),

    template_parameters: $ => seq(
      '(',
      optional(seq($.template_parameter, repeat(seq(',', $.template_parameter)))),
      ')',
    ),

    template_parameter: $ => seq(
      field('name', $.identifier),
      optional(seq('=', field('default', $.argument))),
    ),

    // The name of a process, state, group, network or logger: the rest of the line,
    // evaluated, and never starting with a colon (`process: x` would be a key).
    section_name: $ => seq(
      choice($._first_text, $.expansion, $.string, $._percent),
      repeat($._value_piece),
    ),

    _line: $ => choice(
      $.key_line,
      $.list_line,
      $.flags_line,
      $.directive,
      $.template_use,
      $.conditional,
      $.append_environment,
    ),

    // `KEY: VALUE`, `add KEY: VALUE`, `KEY: [` block.
    key_line: $ => seq(
      optional(field('add', 'add')),
      choice(seq(field('key', $.key), ':'), field('key', alias($._word_key, $.key))),
      optional(field('value', choice($.value, $.block))),
    ),

    // Keys of any section: a process key, a define's name, a host, a topic pattern.
    key: $ => repeat1(choice($._key_text, $.expansion, $.string)),

    // `depends_on: a, b` and the other keys whose value is a list of names.
    list_line: $ => seq(
      optional(field('add', 'add')),
      field('key', alias(choice(...LIST_KEYS), $.key)),
      ':',
      optional(field('value', choice($.list, $.block))),
    ),

    list: $ => commaList($.list_item),

    // `flags: no_pty, forward_x11` of processes and groups.
    flags_line: $ => seq(
      optional(field('add', 'add')),
      field('key', alias('flags', $.key)),
      ':',
      optional(field('value', choice($.flags, $.block))),
    ),

    flags: $ => commaList(alias($.list_item, $.flag)),

    list_item: $ => repeat1(choice($._item_text, $.expansion, $.string, $._percent)),

    value: $ => repeat1($._value_piece),

    _value_piece: $ => choice($.text, $.expansion, $.string, $._percent),

    // A value that is just `[`: value lines up to a line holding only `]`.
    block: $ => seq('[', repeat(seq($._newline, optional($.block_line))), ']'),

    block_line: $ => seq(
      choice(alias($._block_text, $.text), $.expansion, $._percent),
      repeat(choice(alias($._block_more_text, $.text), $.expansion, $._percent)),
    ),

    // `include FILE`, `push_name_prefix: X`, ...: a blank or a colon before the argument.
    directive: $ => seq(
      field('name', alias(choice(...DIRECTIVES), $.directive_name)),
      optional(':'),
      optional(field('argument', alias($._argument_value, $.value))),
    ),

    _argument_value: $ => seq(
      choice(alias($._first_text, $.text), $.expansion, $.string, $._percent),
      repeat($._value_piece),
    ),

    // `use_template: NAME(VALUE, ...)`.
    template_use: $ => seq(
      'use_template',
      optional(':'),
      field('template', choice($.template_name, $.expansion)),
      optional(field('arguments', $.template_arguments)),
    ),

    template_arguments: $ => seq('(', optional($.arguments), ')'),

    // `ifdef NAME: LINE`, `ifndef NAME: LINE`.
    conditional: $ => seq(
      choice('ifdef', 'ifndef'),
      field('name', $.define_name),
      ':',
      optional(field('line', $._line)),
    ),

    // The original's `append environment VAR: VALUE` (also `append environment: VAR=VALUE`).
    append_environment: $ => seq(
      'append',
      'environment',
      optional(':'),
      field('variable', $.identifier),
      choice(':', '='),
      optional(field('value', $.value)),
    ),

    // `%(NAME)` or `%(FUNCTION ARGS)`; calls nest, also inside quotes.
    expansion: $ => seq(
      '%(',
      choice(
        seq(field('function', $.function_name), optional(field('arguments', $.arguments))),
        seq(field('name', choice(alias($._name_text, $.define_name), $.expansion)),
          optional(field('arguments', $.arguments))),
      ),
      ')',
    ),

    function_name: _ => choice(...FUNCTIONS),

    arguments: $ => commaList($.argument),

    argument: $ => repeat1(choice(
      alias($._argument_text, $.text), $.string, $.expansion, $.parenthesized, $._percent)),

    // Balanced parentheses inside a call (`%(shell echo $(date))`).
    parenthesized: $ => seq('(', repeat(choice(
      alias($._argument_text, $.text), $.string, $.expansion, $.parenthesized, $._percent,
      ',')), ')'),

    // A define name as written after `ifdef`, maybe built by calls.
    define_name: $ => repeat1(choice($._key_text, $.expansion)),

    string: $ => seq(
      '"',
      repeat(choice($.string_content, $.escape_sequence, $.expansion,
        alias(token.immediate('%'), $.string_content))),
      token.immediate('"'),
    ),

    string_content: _ => token.immediate(prec(1, /[^"\\%\n]+/)),

    escape_sequence: _ => token.immediate(/\\[^\n]/),

    // A `%` that does not start a call is text.
    _percent: $ => alias('%', $.text),

    text: _ => text(char(''), char('')),
    _first_text: _ => text(`[^\\s#"%:]|%[^\\s#"%(:]`, char('')),
    _item_text: _ => text(char(','), char(',')),
    _argument_text: _ => text(char(',()'), char(',()')),
    _key_text: _ => /([^\s:#"%]|%[^\s:#"%(])+/,
    // A section word or prefix followed by a colon is a key, not a header (`state: x`
    // defines `state`); one token with its colon, so this key's text ends with it.
    _word_key: _ => token(seq(choice(...SECTION_WORDS, 'add', 'append', 'ifdef', 'ifndef'),
      /[ \t]*:/)),
    _name_text: _ => /[^\s,()"%#]+/,
    // In a block a `#` or `"` after the start of a line is text; `]` alone ends it.
    _block_text: _ => text(`[^\\s#%\\]]|%[^\\s(]|\\][^\\s]`, `[^\\s%]|%[^\\s(]`),
    // After a call a `#` is text too, not a comment.
    _block_more_text: _ => token(prec(1, text(`[^\\s%]|%[^\\s(]`, `[^\\s%]|%[^\\s(]`))),

    template_name: _ => /[A-Za-z_][A-Za-z0-9_.\-]*(\/[A-Za-z_][A-Za-z0-9_.\-]*)*/,
    identifier: _ => /[A-Za-z_][A-Za-z0-9_]*/,

    comment: _ => token(seq('#', /.*/)),

    _newline: _ => /\n/,
  },
});
