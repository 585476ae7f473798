; Highlighting of .lnc configuration files: section types and names, keys (those the
; reader knows and others), values, %() calls, directives and comments.

(comment) @comment

; Sections

[
  "instance"
  "defines"
  "hosts"
  "node_map"
  "topics"
  "access"
  "process"
  "state"
  "group"
  "network"
  "logger"
  "template"
  "process_template"
] @keyword.type

(section_name) @type

(template_section
  name: (template_name) @type.definition)

(template_parameter
  name: (identifier) @variable.parameter)

; Keys. Known keys: those of process_keys.py (SCALARS, LISTS, IGNORED) and of the
; instance, state, group and network sections in sections.py, and `undef`.

((key) @property
  (#any-of? @property
    "affinity" "change_directory" "command" "max_output_lines" "node" "output_encoding"
    "output_logfile" "output_logfile_keep_count" "output_logfile_size_limit" "policy"
    "priority" "ready_on_service" "ready_on_topic" "log_level_regex" "ready_regex" "ready_time" "restart"
    "restart_delay" "restart_limit" "stack_size" "term_signal" "term_timeout"
    "watchdog_topic" "max_rss" "max_cpu" "on_limit" "depends_on" "environment" "flags" "parameters" "pass_environment"
    "set_resource_limits" "start_before" "start_on_ready" "bugtracker_url" "documentation"
    "gui" "line_highlight_bg_color" "line_highlight_fg_color" "line_highlight_regexes"
    "mantis_project_id" "max_output_frequency" "max_queued_output_bytes" "notebook"
    "output_buffer_size" "vte_color_style" "warning_msg" "warning_regex" "manager" "name"
    "webui" "webui_auth_file" "webui_port" "webui_tls_cert" "webui_tls_key" "security" "client_key_file" "client_uids" "client_gids" "enable_auto_groups" "groups_opened_default"
    "groups_sorted_default" "check" "down" "min_check_interval" "up" "members"
    "member_interfaces" "preferred_gateways" "undef"))

; Other keys: unknown in the sections with a fixed set of keys, ...

(process_section
  (key_line
    key: (key) @variable
    (#not-any-of? @variable
        "affinity" "change_directory" "command" "max_output_lines" "node" "output_encoding"
        "output_logfile" "output_logfile_keep_count" "output_logfile_size_limit" "policy"
        "priority" "ready_on_service" "ready_on_topic" "log_level_regex" "ready_regex" "ready_time" "restart"
        "restart_delay" "restart_limit" "stack_size" "term_signal" "term_timeout"
        "watchdog_topic" "max_rss" "max_cpu" "on_limit" "depends_on" "environment" "flags" "parameters" "pass_environment"
        "set_resource_limits" "start_before" "start_on_ready" "bugtracker_url" "documentation"
        "gui" "line_highlight_bg_color" "line_highlight_fg_color" "line_highlight_regexes"
        "mantis_project_id" "max_output_frequency" "max_queued_output_bytes" "notebook"
        "output_buffer_size" "vte_color_style" "warning_msg" "warning_regex" "manager" "name"
        "webui" "webui_auth_file" "webui_port" "webui_tls_cert" "webui_tls_key" "security" "client_key_file" "client_uids" "client_gids" "enable_auto_groups" "groups_opened_default"
        "groups_sorted_default" "check" "down" "min_check_interval" "up" "members"
        "member_interfaces" "preferred_gateways" "undef")))

(state_section
  (key_line
    key: (key) @variable
    (#not-any-of? @variable
        "affinity" "change_directory" "command" "max_output_lines" "node" "output_encoding"
        "output_logfile" "output_logfile_keep_count" "output_logfile_size_limit" "policy"
        "priority" "ready_on_service" "ready_on_topic" "log_level_regex" "ready_regex" "ready_time" "restart"
        "restart_delay" "restart_limit" "stack_size" "term_signal" "term_timeout"
        "watchdog_topic" "max_rss" "max_cpu" "on_limit" "depends_on" "environment" "flags" "parameters" "pass_environment"
        "set_resource_limits" "start_before" "start_on_ready" "bugtracker_url" "documentation"
        "gui" "line_highlight_bg_color" "line_highlight_fg_color" "line_highlight_regexes"
        "mantis_project_id" "max_output_frequency" "max_queued_output_bytes" "notebook"
        "output_buffer_size" "vte_color_style" "warning_msg" "warning_regex" "manager" "name"
        "webui" "webui_auth_file" "webui_port" "webui_tls_cert" "webui_tls_key" "security" "client_key_file" "client_uids" "client_gids" "enable_auto_groups" "groups_opened_default"
        "groups_sorted_default" "check" "down" "min_check_interval" "up" "members"
        "member_interfaces" "preferred_gateways" "undef")))

(group_section
  (key_line
    key: (key) @variable
    (#not-any-of? @variable
        "affinity" "change_directory" "command" "max_output_lines" "node" "output_encoding"
        "output_logfile" "output_logfile_keep_count" "output_logfile_size_limit" "policy"
        "priority" "ready_on_service" "ready_on_topic" "log_level_regex" "ready_regex" "ready_time" "restart"
        "restart_delay" "restart_limit" "stack_size" "term_signal" "term_timeout"
        "watchdog_topic" "max_rss" "max_cpu" "on_limit" "depends_on" "environment" "flags" "parameters" "pass_environment"
        "set_resource_limits" "start_before" "start_on_ready" "bugtracker_url" "documentation"
        "gui" "line_highlight_bg_color" "line_highlight_fg_color" "line_highlight_regexes"
        "mantis_project_id" "max_output_frequency" "max_queued_output_bytes" "notebook"
        "output_buffer_size" "vte_color_style" "warning_msg" "warning_regex" "manager" "name"
        "webui" "webui_auth_file" "webui_port" "webui_tls_cert" "webui_tls_key" "security" "client_key_file" "client_uids" "client_gids" "enable_auto_groups" "groups_opened_default"
        "groups_sorted_default" "check" "down" "min_check_interval" "up" "members"
        "member_interfaces" "preferred_gateways" "undef")))

(instance_section
  (key_line
    key: (key) @variable
    (#not-any-of? @variable
        "affinity" "change_directory" "command" "max_output_lines" "node" "output_encoding"
        "output_logfile" "output_logfile_keep_count" "output_logfile_size_limit" "policy"
        "priority" "ready_on_service" "ready_on_topic" "log_level_regex" "ready_regex" "ready_time" "restart"
        "restart_delay" "restart_limit" "stack_size" "term_signal" "term_timeout"
        "watchdog_topic" "max_rss" "max_cpu" "on_limit" "depends_on" "environment" "flags" "parameters" "pass_environment"
        "set_resource_limits" "start_before" "start_on_ready" "bugtracker_url" "documentation"
        "gui" "line_highlight_bg_color" "line_highlight_fg_color" "line_highlight_regexes"
        "mantis_project_id" "max_output_frequency" "max_queued_output_bytes" "notebook"
        "output_buffer_size" "vte_color_style" "warning_msg" "warning_regex" "manager" "name"
        "webui" "webui_auth_file" "webui_port" "webui_tls_cert" "webui_tls_key" "security" "client_key_file" "client_uids" "client_gids" "enable_auto_groups" "groups_opened_default"
        "groups_sorted_default" "check" "down" "min_check_interval" "up" "members"
        "member_interfaces" "preferred_gateways" "undef")))

(network_section
  (key_line
    key: (key) @variable
    (#not-any-of? @variable
        "affinity" "change_directory" "command" "max_output_lines" "node" "output_encoding"
        "output_logfile" "output_logfile_keep_count" "output_logfile_size_limit" "policy"
        "priority" "ready_on_service" "ready_on_topic" "log_level_regex" "ready_regex" "ready_time" "restart"
        "restart_delay" "restart_limit" "stack_size" "term_signal" "term_timeout"
        "watchdog_topic" "max_rss" "max_cpu" "on_limit" "depends_on" "environment" "flags" "parameters" "pass_environment"
        "set_resource_limits" "start_before" "start_on_ready" "bugtracker_url" "documentation"
        "gui" "line_highlight_bg_color" "line_highlight_fg_color" "line_highlight_regexes"
        "mantis_project_id" "max_output_frequency" "max_queued_output_bytes" "notebook"
        "output_buffer_size" "vte_color_style" "warning_msg" "warning_regex" "manager" "name"
        "webui" "webui_auth_file" "webui_port" "webui_tls_cert" "webui_tls_key" "security" "client_key_file" "client_uids" "client_gids" "enable_auto_groups" "groups_opened_default"
        "groups_sorted_default" "check" "down" "min_check_interval" "up" "members"
        "member_interfaces" "preferred_gateways" "undef")))

(template_section
  (key_line
    key: (key) @variable
    (#not-any-of? @variable
        "affinity" "change_directory" "command" "max_output_lines" "node" "output_encoding"
        "output_logfile" "output_logfile_keep_count" "output_logfile_size_limit" "policy"
        "priority" "ready_on_service" "ready_on_topic" "log_level_regex" "ready_regex" "ready_time" "restart"
        "restart_delay" "restart_limit" "stack_size" "term_signal" "term_timeout"
        "watchdog_topic" "max_rss" "max_cpu" "on_limit" "depends_on" "environment" "flags" "parameters" "pass_environment"
        "set_resource_limits" "start_before" "start_on_ready" "bugtracker_url" "documentation"
        "gui" "line_highlight_bg_color" "line_highlight_fg_color" "line_highlight_regexes"
        "mantis_project_id" "max_output_frequency" "max_queued_output_bytes" "notebook"
        "output_buffer_size" "vte_color_style" "warning_msg" "warning_regex" "manager" "name"
        "webui" "webui_auth_file" "webui_port" "webui_tls_cert" "webui_tls_key" "security" "client_key_file" "client_uids" "client_gids" "enable_auto_groups" "groups_opened_default"
        "groups_sorted_default" "check" "down" "min_check_interval" "up" "members"
        "member_interfaces" "preferred_gateways" "undef")))

; ... define names, hosts and logical nodes, topic patterns.
(defines_section
  [
    (key_line
      key: (key) @constant)
    (conditional
      line: (key_line
        key: (key) @constant))
  ])

(hosts_section
  (key_line
    key: (key) @label))

(node_map_section
  (key_line
    key: (key) @label))

[
  (topics_section
    (key_line
      key: (key) @string.special))
  (logger_section
    (key_line
      key: (key) @string.special))
  (access_section
    (key_line
      key: (key) @string.special))
]

; Values: a number or boolean as the whole value of a key, other text as strings,
; directive arguments as paths.

(key_line
  value: (value
    .
    (text) @number
    .)
  (#match? @number "^[-+]?[0-9][0-9.]*[a-zA-Z]*$"))

(key_line
  value: (value
    .
    (text) @boolean
    .)
  (#any-of? @boolean "true" "false"))

(key_line
  value: (value
    (text) @string)
  (#not-match? @string "^[-+]?[0-9][0-9.]*[a-zA-Z]*$")
  (#not-any-of? @string "true" "false"))

(append_environment
  value: (value
    (text) @string))

[
  (argument
    (text) @string)
  (parenthesized
    (text) @string)
  (block_line
    (text) @string)
]

(directive
  argument: (value
    (text) @string.special.path))

(string) @string

(escape_sequence) @string.escape

(flag) @constant.builtin

(list_item) @type

; %() calls

(expansion
  [
    "%("
    ")"
  ] @punctuation.special)

(function_name) @function.builtin

((define_name) @constant.builtin
  (#any-of? @constant.builtin
    "CURDIR" "CURRENT" "_PROCESS" "_FULL_PROCESS" "instance_name" "hostname" "manager"
    "LN_PYTHON" "LN_PYTHONPATH"))

((define_name) @constant
  (#not-any-of? @constant
    "CURDIR" "CURRENT" "_PROCESS" "_FULL_PROCESS" "instance_name" "hostname" "manager"
    "LN_PYTHON" "LN_PYTHONPATH"))

; Directives

((directive_name) @keyword.import
  (#any-of? @keyword.import
    "include" "optional_include" "include_glob" "optional_include_glob" "pipe_include"))

((directive_name) @keyword.directive
  (#not-any-of? @keyword.directive
    "include" "optional_include" "include_glob" "optional_include_glob" "pipe_include"))

"use_template" @keyword.directive

(template_use
  template: (template_name) @function.macro)

(conditional
  [
    "ifdef"
    "ifndef"
  ] @keyword.conditional)

[
  "add"
  "append"
  "environment"
] @keyword

(append_environment
  variable: (identifier) @variable)

; Punctuation

[
  ":"
  "="
] @punctuation.delimiter

"," @punctuation.delimiter

[
  "["
  "]"
] @punctuation.bracket

(template_parameters
  [
    "("
    ")"
  ] @punctuation.bracket)

(template_arguments
  [
    "("
    ")"
  ] @punctuation.bracket)

(parenthesized
  [
    "("
    ")"
  ] @punctuation.bracket)
