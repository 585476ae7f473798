" File types of links_and_nodes (docs/editors.md), for Vim and Neovim: `lnc` for
" configuration files, `lnmd` for message definitions, which have no extension and are
" recognised by their folder (message_definitions/ or service_definitions/ somewhere above).
autocmd BufNewFile,BufRead *.lnc,*.lnc.in setfiletype lnc
autocmd BufNewFile,BufRead */message_definitions/*,*/service_definitions/*
      \ if expand('<afile>:t') =~# '^\h\w*$' && expand('<afile>:t') !~# '^\(SConscript\|SConstruct\|Makefile\|README\|LICENSE\)$'
      \ | setfiletype lnmd | endif
