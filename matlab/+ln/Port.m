% ln.Port — what ln.Publisher and ln.Subscriber share (docs/matlab.md): the port of one topic
% on a client, opened with the md's layout from the manager, a zero sample of the md, the
% count of ports at the other end, and closing when cleared.
classdef Port < handle
  properties (SetAccess = private)
    topic = ''
    md = ''
    client      % the ln.Client, kept alive while the port exists
  end
  properties (Access = protected)
    id = 0
  end

  methods
    function p = Port(client, op, topic, md, buffers)
      % OP is 'publish' or 'subscribe'.
      layout = client.md_layout(md);
      if ~strcmp(layout.kind, 'message')
        error('ln:EMD', 'md %s is a %s, not a message', md, layout.kind);
      end
      section = layout.sections(1);
      p.id = ln_mex(op, client.id, topic, md, layout.layout_hash, layout.signature, ...
                    section.size, section.names, buffers);
      p.client = client;
      p.topic = topic;
      p.md = md;
    end

    function sample = sample(p)
      % A struct with every field of the md, all zero.
      sample = ln_mex('zero', p.id, 0);
    end

    function delete(p)
      if p.id ~= 0
        ln_mex('close', p.id);
        p.id = 0;
      end
    end
  end

  methods (Access = protected)
    function n = peers(p)
      % Subscribers of a publisher, publishers of a subscriber.
      n = ln_mex('count', p.id);
    end
  end
end
