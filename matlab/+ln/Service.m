% ln.Service — a caller's handle of one service (docs/matlab.md): call(request, timeout) packs
% the request struct (dynamic fields take the length of the value) and returns the response
% as a struct.  Made by ln.Client/service; clearing it releases the connection.
classdef Service < handle
  properties (SetAccess = private)
    name = ''
    md = ''
    client      % the ln.Client, kept alive while the handle exists
  end
  properties (Access = private)
    id = 0
  end

  methods
    function svc = Service(client, name, md)
      layout = client.md_layout(md);
      if ~strcmp(layout.kind, 'service')
        error('ln:EMD', 'md %s is a %s, not a service', md, layout.kind);
      end
      sig = strsplit(layout.signature, '|');
      req = layout.sections(1);
      resp = layout.sections(2);
      svc.id = ln_mex('service', client.id, name, md, layout.layout_hash, layout.signature, ...
                      sig{1}, req.size, req.names, sig{2}, resp.size, resp.names);
      svc.client = client;
      svc.name = name;
      svc.md = md;
    end

    function response = call(svc, request, timeout)
      % response = svc.call(REQUEST, TIMEOUT): TIMEOUT s (default 10).
      if nargin < 3
        timeout = 10;
      end
      response = ln_mex('call', svc.id, request, timeout);
    end

    function request = request(svc)
      % A request struct with every field, all zero (dynamic fields empty).
      request = ln_mex('zero', svc.id, 0);
    end

    function delete(svc)
      if svc.id ~= 0
        ln_mex('close', svc.id);
        svc.id = 0;
      end
    end
  end
end
