% ln.Publisher — a publisher of one topic (docs/matlab.md): write(sample) packs a struct with
% the md's fields into the md's bytes and publishes it.  Made by ln.Client/publish; clearing
% it (or its client) unpublishes.
classdef Publisher < handle
  properties (SetAccess = private)
    topic = ''
    md = ''
    client      % the ln.Client, kept alive while the publisher exists
  end
  properties (Access = private)
    id = 0
  end

  methods
    function p = Publisher(client, topic, md, buffers)
      layout = client.md_layout(md);
      if ~strcmp(layout.kind, 'message')
        error('ln:EMD', 'md %s is a %s, not a message', md, layout.kind);
      end
      section = layout.sections(1);
      p.id = ln_mex('publish', client.id, topic, md, layout.layout_hash, layout.signature, ...
                    section.size, section.names, buffers);
      p.client = client;
      p.topic = topic;
      p.md = md;
    end

    function write(p, sample, timeout)
      % p.write(SAMPLE): SAMPLE is a struct with every field of the md (p.sample() gives one).
      if nargin < 3
        timeout = 1;
      end
      ln_mex('write', p.id, sample, timeout);
    end

    function sample = sample(p)
      % A struct with every field of the md, all zero.
      sample = ln_mex('zero', p.id, 0);
    end

    function n = subscribers(p)
      n = ln_mex('count', p.id);
    end

    function delete(p)
      if p.id ~= 0
        ln_mex('close', p.id);
        p.id = 0;
      end
    end
  end
end
