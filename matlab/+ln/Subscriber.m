% ln.Subscriber — a subscriber of one topic (docs/matlab.md): read(timeout) gives the next
% sample as a struct with the md's fields, [] when none came in time.  Made by
% ln.Client/subscribe; clearing it (or its client) unsubscribes.
classdef Subscriber < handle
  properties (SetAccess = private)
    topic = ''
    md = ''
    client      % the ln.Client, kept alive while the subscriber exists
  end
  properties (Access = private)
    id = 0
  end

  methods
    function s = Subscriber(client, topic, md, buffers)
      layout = client.md_layout(md);
      if ~strcmp(layout.kind, 'message')
        error('ln:EMD', 'md %s is a %s, not a message', md, layout.kind);
      end
      section = layout.sections(1);
      s.id = ln_mex('subscribe', client.id, topic, md, layout.layout_hash, ...
                    layout.signature, section.size, section.names, buffers);
      s.client = client;
      s.topic = topic;
      s.md = md;
    end

    function [sample, info] = read(s, timeout)
      % [SAMPLE, INFO] = s.read(TIMEOUT): waits up to TIMEOUT s (default 1; 0 does not wait,
      % a negative one waits forever) and returns [] if no sample came.  INFO has seq,
      % timestamp (s since the epoch) and overruns.
      if nargin < 2
        timeout = 1;
      end
      [sample, info] = ln_mex('read', s.id, timeout);
    end

    function sample = sample(s)
      % A struct with every field of the md, all zero.
      sample = ln_mex('zero', s.id, 0);
    end

    function n = publishers(s)
      n = ln_mex('count', s.id);
    end

    function delete(s)
      if s.id ~= 0
        ln_mex('close', s.id);
        s.id = 0;
      end
    end
  end
end
