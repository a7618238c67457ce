// HerdSample.cs - drives the sample scene's herd: spreads the instances over a field, lets them
// wander at their own speeds, sends a few to graze or flee now and then, logs footsteps and carries
// a marker on the first cow's head socket. Bake its palette and manifest first (README.md).
using Crowdbake;
using UnityEngine;

public sealed class HerdSample : MonoBehaviour
{
    public CrowdbakeHerd herd;
    public Transform headMarker; // optional: follows instance 0's "Head_end" socket
    public float spacing = 3;
    public int seed = 1;

    System.Random random;
    float nextChange;

    void Start()
    {
        random = new System.Random(seed);
        int side = Mathf.CeilToInt(Mathf.Sqrt(herd.Count));
        for (int i = 0; i < herd.Count; ++i) {
            herd.Place(i, new Vector3((i % side) * spacing, 0, (i / side) * spacing), (float)random.NextDouble() * 360, 0.9f + 0.2f * (float)random.NextDouble());
            herd.SetSpeed(i, 0.8f + 0.6f * (float)random.NextDouble());
        }
        herd.Footstep += (e) => { if (e.instance == 0) Debug.Log("cow 0: " + e.foot + (e.lands ? " lands" : " lifts") + " at " + e.time); };
        Debug.Log("herd: " + herd.BonePassReason); // 400 cows: the bone pass, where this machine has compute shaders
    }

    void Update()
    {
        if (Time.time >= nextChange) {
            nextChange = Time.time + 2;
            int i = random.Next(herd.Count);
            string[] moods = { "wander", "idle", "flee" };
            string mood = moods[random.Next(moods.Length)];
            herd.SetState(i, mood, 0.3f);
            if (mood == "flee") herd.SetSpeed(i, 6);
        }
        if (headMarker != null) {
            Matrix4x4 m = herd.SocketMatrixAt(0, herd.Socket("Head_end"));
            headMarker.SetPositionAndRotation(m.MultiplyPoint3x4(Vector3.zero), m.rotation);
        }
    }
}
