-- Neovim setup for links_and_nodes files (docs/editors.md): the language server ln_lsp
-- (Neovim's own vim.lsp.config on 0.11+, else nvim-lspconfig) and the Tree-sitter parsers
-- of editors/tree-sitter-lnc and editors/tree-sitter-lnmd (through nvim-treesitter).
-- Put editors/nvim on 'runtimepath', then: require('links_and_nodes').setup({ ... })
local M = {}

-- editors/ of the checkout this file lies in (editors/nvim/lua/links_and_nodes/init.lua).
local editors = vim.fn.fnamemodify(debug.getinfo(1, 'S').source:sub(2), ':p:h:h:h:h')

M.defaults = {
  cmd = { 'ln_lsp' },
  -- As ln_lsp reads them (python/links_and_nodes/manager/frontends/lsp/settings.py); like ln_manager check.
  settings = { defines = {}, mdDirs = {}, strict = false, shellTimeout = 2 },
  lsp = true,
  treesitter = true,
}

local function server_settings(settings)
  local out = vim.deepcopy(settings)
  out.mdDirs = vim.tbl_map(function(dir)
    return vim.fn.fnamemodify(vim.fn.expand(dir), ':p')
  end, settings.mdDirs or {})
  return out
end

function M.setup_lsp(opts)
  local settings = server_settings(opts.settings)
  local config = {
    cmd = opts.cmd,
    filetypes = { 'lnc', 'lnmd' },
    init_options = settings,
    settings = { ln = settings },
  }
  if vim.fn.has('nvim-0.11') == 1 then
    config.root_markers = { '.git' }
    vim.lsp.config('ln_lsp', config)
    vim.lsp.enable('ln_lsp')
    return
  end
  local ok, configs = pcall(require, 'lspconfig.configs')
  if not ok then
    vim.notify('links_and_nodes: nvim-lspconfig is not installed', vim.log.levels.WARN)
    return
  end
  if not configs.ln_lsp then
    config.root_dir = require('lspconfig.util').root_pattern('.git')
    config.single_file_support = true
    configs.ln_lsp = { default_config = config }
  end
  require('lspconfig').ln_lsp.setup({})
end

-- The parsers' install_info for nvim-treesitter: built from the grammar folders here.
local GRAMMARS = { lnc = 'tree-sitter-lnc', lnmd = 'tree-sitter-lnmd' }

local function parser_files(dir)
  local files = { 'src/parser.c' }
  if vim.fn.filereadable(dir .. '/src/scanner.c') == 1 then
    table.insert(files, 'src/scanner.c')
  end
  return files
end

function M.setup_treesitter()
  local ok, parsers = pcall(require, 'nvim-treesitter.parsers')
  if not ok then
    return -- no nvim-treesitter: the Vim syntax files of editors/nvim/syntax highlight
  end
  if parsers.get_parser_configs then -- nvim-treesitter's master branch
    local configs = parsers.get_parser_configs()
    for lang, folder in pairs(GRAMMARS) do
      local dir = editors .. '/' .. folder
      configs[lang] = {
        install_info = {
          url = dir,
          files = parser_files(dir),
          requires_generate_from_grammar = false,
        },
        filetype = lang,
      }
    end
  else -- its main branch: parsers are registered when it asks for them
    vim.api.nvim_create_autocmd('User', {
      pattern = 'TSUpdate',
      callback = function()
        for lang, folder in pairs(GRAMMARS) do
          require('nvim-treesitter.parsers')[lang] = {
            install_info = { path = editors .. '/' .. folder, queries = 'queries' },
          }
        end
      end,
    })
  end
  -- Highlight with the parser once it is installed (:TSInstall lnc lnmd).
  vim.api.nvim_create_autocmd('FileType', {
    pattern = { 'lnc', 'lnmd' },
    callback = function(args)
      pcall(vim.treesitter.start, args.buf)
    end,
  })
end

function M.setup(opts)
  opts = vim.tbl_deep_extend('force', M.defaults, opts or {})
  if opts.lsp then
    M.setup_lsp(opts)
  end
  if opts.treesitter then
    M.setup_treesitter()
  end
end

return M
