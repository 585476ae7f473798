" Vim syntax for links_and_nodes configuration files (.lnc): a short fallback for Vim and for
" Neovim without the Tree-sitter parser (editors/tree-sitter-lnc), which highlights more.
if exists('b:current_syntax')
  finish
endif

syn match   lncComment   "#.*$" contains=@Spell
syn region  lncString    start=+"+ skip=+\\[\\"]+ end=+"+ contains=lncCall
syn region  lncCall      matchgroup=lncCallDelim start="%(" end=")" contains=lncCall,lncString,lncFunction
syn match   lncFunction  "\%(%(\s*\)\@<=\<\(env\|dirname\|basename\|subst\|get_port_from_string\|shell\|ifdef\|ifndef\|ifeq\|ifexists\)\>" contained
syn match   lncSection   "^\s*\(instance\|defines\|hosts\|node_map\|network\|topics\|process\|state\|group\|template\|process_template\|logger\)\>\(\s*:\)\@!"
syn match   lncDirective "^\s*\(include\|optional_include\|include_glob\|optional_include_glob\|pipe_include\|push_name_prefix\|pop_name_prefix\|add_message_definition_dir\|requires_version\|undef\|ifdef\|ifndef\)\>"
syn match   lncKey       "^\s*\(add\s\+\|append\s\+environment\s\+\)\=[^ \t:#"]\+\ze\s*:" contains=lncAdd
syn match   lncAdd       "\<\(add\|append\)\>" contained
syn match   lncBlock     "\[\s*$\|^\s*\]"

hi def link lncComment   Comment
hi def link lncString    String
hi def link lncCallDelim Special
hi def link lncFunction  Function
hi def link lncSection   Statement
hi def link lncDirective PreProc
hi def link lncKey       Identifier
hi def link lncAdd       Keyword
hi def link lncBlock     Delimiter

let b:current_syntax = 'lnc'
