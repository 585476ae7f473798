; Folds of .lnc files: each section from its header to its last line, and [ ] blocks.

[
  (instance_section)
  (defines_section)
  (hosts_section)
  (node_map_section)
  (topics_section)
  (access_section)
  (process_section)
  (state_section)
  (group_section)
  (network_section)
  (logger_section)
  (template_section)
  (block)
] @fold
