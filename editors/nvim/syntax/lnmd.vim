" Vim syntax for links_and_nodes message definitions (docs/message_definitions.md): a short
" fallback for Vim and for Neovim without the Tree-sitter parser (editors/tree-sitter-lnmd).
if exists('b:current_syntax')
  finish
endif

syn match   lnmdComment  "#.*$" contains=@Spell
syn match   lnmdKind     "^\s*\(service\|event\)\s*\($\|#\)\@="
syn match   lnmdSection  "^\s*\(request\|response\|connect\|call\)\s*\($\|#\)\@="
syn match   lnmdDefine   "^\s*define\>\|\<as\>"
syn region  lnmdString   start=+"+ end=+"+ oneline
syn match   lnmdType     "^\s*\<\(char\|u\=int\(8\|16\|32\|64\)_t\|int\|short\|float\|double\|float32_t\|float64_t\)\>"
syn match   lnmdNumber   "\<\(0[xX]\x\+\|\d\+\)\>"

hi def link lnmdComment  Comment
hi def link lnmdKind     Statement
hi def link lnmdSection  Label
hi def link lnmdDefine   PreProc
hi def link lnmdString   String
hi def link lnmdType     Type
hi def link lnmdNumber   Number

let b:current_syntax = 'lnmd'
