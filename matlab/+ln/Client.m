% ln.Client — a links_and_nodes client for MATLAB and GNU Octave (docs/matlab.md): connects to
% the manager, makes publishers, subscribers and service handles, and reads message
% definitions at run time from the manager (its `md_layout` answer), so nothing is generated.
classdef Client < handle
  properties (SetAccess = private)
    name = ''   % the name the manager gave this client
    id = 0      % the handle in ln_mex's table
  end
  properties (Access = private)
    layouts     % md name -> the manager's md_layout answer
  end

  methods
    function c = Client(name, manager)
      % ln.Client(NAME) connects to the manager at $LN_MANAGER; ln.Client(NAME, 'HOST:PORT')
      % to that one.
      if nargin < 2
        manager = '';
      end
      c.layouts = containers.Map();
      c.id = ln_mex('create', name, manager);
      c.name = ln_mex('name', c.id);
    end

    function p = publish(c, topic, md, buffers)
      % p = c.publish(TOPIC, MD) publishes TOPIC with md MD (e.g. 'robot/joint_state').
      if nargin < 4
        buffers = 1;
      end
      p = ln.Publisher(c, topic, md, buffers);
    end

    function s = subscribe(c, topic, md, buffers)
      % s = c.subscribe(TOPIC, MD, BUFFERS): BUFFERS 1 (default) reads the newest sample,
      % N > 1 every sample while at most N behind.
      if nargin < 4
        buffers = 1;
      end
      s = ln.Subscriber(c, topic, md, buffers);
    end

    function svc = service(c, name, md)
      % svc = c.service(NAME, MD): a handle for repeated calls of service NAME.
      svc = ln.Service(c, name, md);
    end

    function response = call(c, name, md, request, timeout)
      % response = c.call(SERVICE, MD, REQUEST, TIMEOUT): one call (TIMEOUT s, default 10).
      if nargin < 5
        timeout = 10;
      end
      svc = ln.Service(c, name, md);
      response = svc.call(request, timeout);
      delete(svc);
    end

    function value = param_get(c, service, name)
      % value = c.param_get(BLOCK_SERVICE, NAME): a parameter's value as the program's loop
      % has it ('arm.controller.parameters.gains', 'kp'); NAME '' gives a struct of all.
      result = param_query(c, service, 'get', name, '');
      if isempty(name)
        value = struct();
        for p = result.parameters(:).'
          value.(p.name) = row(p.value);
        end
      else
        value = row(result.parameters(1).value);
      end
    end

    function generation = param_set(c, service, name, value)
      % generation = c.param_set(BLOCK_SERVICE, NAME, VALUE): overrides a parameter; the
      % block's generation of the change.
      result = param_query(c, service, 'set', name, jsonencode(value));
      generation = result.generation;
    end

    function result = control(c, command)
      % result = c.control(STRUCT): one manager command (docs/protocol.md, "Control"), e.g.
      % struct('op', 'topic_info', 'name', 'arm.state'); the answer as a struct.
      result = jsondecode(ln_mex('control', c.id, jsonencode(command)));
    end

    function layout = md_layout(c, md)
      % The manager's md_layout answer for MD (kept for the client's lifetime).
      if ~c.layouts.isKey(md)
        c.layouts(md) = c.control(struct('op', 'md_layout', 'name', md));
      end
      layout = c.layouts(md);
    end

    function delete(c)
      % Disconnects; the client's ports and service handles are closed with it.
      if c.id ~= 0
        ln_mex('close', c.id);
        c.id = 0;
      end
    end
  end
end

function result = param_query(c, service, op, name, value)
  request = struct('op', op, 'name', name, 'value', value);
  response = c.call(service, 'ln/parameters/query', request, 10);
  if response.status ~= 0
    error(['ln:' response.error], '%s: %s', service, response.reason);
  end
  result = jsondecode(response.result);
end

function v = row(v)
  if isnumeric(v) || islogical(v)
    v = reshape(v, 1, []);
  end
end
