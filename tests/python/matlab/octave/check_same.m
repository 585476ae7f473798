% check_same(GOT, WANT, PATH) — errors naming the first field whose value, class or size
% differs (rows, not columns: the client returns row vectors); structs field by field.
function check_same(got, want, path)
  if nargin < 3
    path = 'sample';
  end
  if ~strcmp(class(got), class(want)) || ~isequal(size(got), size(want))
    error('check:differs', '%s: got %s %s, want %s %s', path, class(got), mat2str(size(got)), ...
          class(want), mat2str(size(want)));
  end
  if isstruct(want)
    if ~isequal(sort(fieldnames(got)), sort(fieldnames(want)))
      error('check:differs', '%s: fields %s, want %s', path, strjoin(fieldnames(got)', ','), ...
            strjoin(fieldnames(want)', ','));
    end
    for i = 1:numel(want)
      for f = fieldnames(want)'
        check_same(got(i).(f{1}), want(i).(f{1}), sprintf('%s(%d).%s', path, i, f{1}));
      end
    end
  elseif ~isequal(got, want)
    error('check:differs', '%s: got %s, want %s', path, mat2str(got), mat2str(want));
  end
end
